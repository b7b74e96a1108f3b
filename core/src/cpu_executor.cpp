// The CPU executor: candidate selection, then every candidate ray of the
// batch traced or walked, parallel over jobs and over fixed chunks of rays
// with TBB. Each ray writes its own slot, so results never depend on the
// thread count, and buffers keep their capacity from step to step.
#include "rtcd/cpu_executor.hpp"

#include "parallel.hpp"
#include "rtcd/error.hpp"
#include "rtcd/kernel/classify.h"
#include "rtcd/kernel/volumes.h"
#include "rtcd/kernel/walk.h"

namespace rtcd {
namespace {

static_assert(sizeof(Eigen::Vector3f) == sizeof(rtcd_vec3), "positions are handed to the kernel as packed floats");
static_assert(sizeof(Mesh::Triangle) == 3 * sizeof(rtcd_uint) && sizeof(Mesh::Neighbors) == 3 * sizeof(rtcd_int));

rtcd_vec3 to_kernel(const Eigen::Vector3f& v) { return rtcd_v3(v.x(), v.y(), v.z()); }
rtcd_vec3 to_kernel(const Eigen::Vector3d& v) { return rtcd_v3(float(v.x()), float(v.y()), float(v.z())); }

// Rays per parallel chunk, and the least rays worth handing to other threads:
// a traced ray costs tens of walks, so full batches go parallel far sooner.
constexpr size_t kChunk = 128;
constexpr size_t kParallelWalks = 1024;
constexpr size_t kParallelTraces = 64;

class CpuExecutor final : public RayExecutor {
 public:
  explicit CpuExecutor(std::unique_ptr<MeshTracerFactory> tracers) : factory_(std::move(tracers)) {}

  void add_shape(std::shared_ptr<const Shape> shape) override {
    const Mesh* mesh = shape->mesh();
    tracers_.push_back(mesh ? factory_->build(*mesh) : nullptr);
    shapes_.push_back(std::move(shape));
  }

  void execute(std::span<const RayJob> jobs, const Config& config,
               std::span<std::vector<RayOutcome>> outcomes) override {
    if (candidates_.size() < jobs.size()) candidates_.resize(jobs.size());
    size_t work = 0;
    for (const RayJob& job : jobs) work += job.iterative ? job.tracked.size() : shapes_[job.source]->sources().origins.size();
    const bool walks = !jobs.empty() && jobs.front().iterative;  // the pipeline never mixes modes in a batch
    if (walks) {
      // Walks are short and even: one pass per job, candidates walked as found.
      for_each_index(jobs.size(), work >= kParallelWalks, [&](size_t j) {
        select(jobs[j], candidates_[j]);
        outcomes[j].resize(candidates_[j].size());
        for (size_t k = 0; k < candidates_[j].size(); ++k) outcomes[j][k] = trace(jobs[j], candidates_[j][k], config);
      });
      return;
    }
    // Traced rays cost far more and vary: select per job, then spread the
    // batch's rays over threads in fixed chunks.
    for_each_index(jobs.size(), work >= kParallelWalks, [&](size_t j) {
      select(jobs[j], candidates_[j]);
      outcomes[j].resize(candidates_[j].size());
    });
    chunks_.clear();
    size_t rays = 0;
    for (uint32_t j = 0; j < jobs.size(); ++j) {
      const uint32_t n = uint32_t(candidates_[j].size());
      for (uint32_t begin = 0; begin < n; begin += kChunk) chunks_.push_back({j, begin, std::min<uint32_t>(n, begin + kChunk)});
      rays += n;
    }
    for_each_index(chunks_.size(), rays >= kParallelTraces, [&](size_t c) {
      const Chunk& chunk = chunks_[c];
      const RayJob& job = jobs[chunk.job];
      for (uint32_t k = chunk.begin; k < chunk.end; ++k)
        outcomes[chunk.job][k] = trace(job, candidates_[chunk.job][k], config);
    });
  }

 private:
  // A candidate ray in the target's frame, rounded to the kernel's floats.
  struct Candidate {
    uint32_t vertex;
    int32_t start;  // iterative: the walk's first triangle
    rtcd_vec3 origin, direction;
  };
  struct Chunk {
    uint32_t job, begin, end;
  };

  void select(const RayJob& job, std::vector<Candidate>& out) const {
    out.clear();
    if (job.overlap.empty()) return;
    const RaySources& rs = shapes_[job.source]->sources();
    auto consider = [&](uint32_t vertex, int32_t start) {
      if (rs.directions[vertex].isZero()) return;  // a vertex with no normal casts no ray
      const Eigen::Vector3d p = job.rotation * rs.origins[vertex].cast<double>() + job.translation;
      if (!job.overlap.contains(p)) return;
      out.push_back({vertex, start, to_kernel(p), to_kernel(Eigen::Vector3d(job.rotation * rs.directions[vertex].cast<double>()))});
    };
    if (job.iterative) {
      for (const TrackedRay& r : job.tracked) consider(r.vertex, r.triangle);
    } else {
      for (uint32_t v = 0; v < rs.origins.size(); ++v) consider(v, -1);
    }
  }

  RayOutcome trace(const RayJob& job, const Candidate& c, const Config& config) const {
    RayOutcome o;
    o.vertex = c.vertex;
    const Shape& target = *shapes_[job.target];
    const float extension = float(config.distance_extension);
    int status = RTCD_LINE_MISS;
    float t = 0.0f;
    if (const Mesh* mesh = target.mesh()) {
      const auto normals = mesh->triangle_normals();
      auto leaves_through = [&](int32_t tri) { return rtcd_dot(c.direction, to_kernel(normals[tri])) > 0.0f; };
      if (job.iterative) {
        const rtcd_ray ray = rtcd_make_ray(c.origin, c.direction);
        const rtcd_walk_result w =
            rtcd_walk(&ray, reinterpret_cast<const rtcd_vec3*>(mesh->positions().data()),
                      reinterpret_cast<const rtcd_uint*>(mesh->triangles().data()),
                      reinterpret_cast<const rtcd_int*>(mesh->neighbors().data()), mesh->zero_area().data(), c.start,
                      config.max_walk_steps);
        status = w.status;
        t = w.t;
        o.triangle = w.triangle;
        o.walk_steps = w.steps;
      } else {
        const MeshTracer& tracer = *tracers_[job.target];
        // Inward ray: a first hit leaving the target means the origin is inside.
        const TraceHit in = tracer.first_hit(rtcd_make_ray(c.origin, c.direction), 3.0e38f);
        if (in.triangle >= 0 && leaves_through(in.triangle)) {
          status = RTCD_LINE_HIT;
          t = in.t;
          o.triangle = in.triangle;
        } else if (config.predictive) {
          // Predictive ray: outward, no further than distance_extension.
          const TraceHit out = tracer.first_hit(rtcd_make_ray(c.origin, rtcd_neg(c.direction)), extension);
          o.predictive_cast = 1;
          if (out.triangle >= 0 && leaves_through(out.triangle)) {
            status = RTCD_LINE_BEHIND;
            t = -out.t;
            o.triangle = out.triangle;
          }
        }
      }
    } else {
      const auto& shape = target.geometry();
      const rtcd_volume_hit h =
          std::holds_alternative<Sphere>(shape)
              ? rtcd_sphere_line(c.origin, c.direction, float(std::get<Sphere>(shape).radius))
          : std::holds_alternative<Box>(shape)
              ? rtcd_box_line(c.origin, c.direction, to_kernel(std::get<Box>(shape).half_extents.cast<float>().eval()))
              : rtcd_halfspace_line(c.origin, c.direction);
      status = h.status;
      t = h.t;
      o.triangle = h.face;
    }
    o.status = uint8_t(status);
    o.kind = uint8_t(rtcd_classify(status, t, config.predictive, extension));
    o.t = t;
    return o;
  }

  std::unique_ptr<MeshTracerFactory> factory_;
  std::vector<std::shared_ptr<const Shape>> shapes_;
  std::vector<std::unique_ptr<MeshTracer>> tracers_;  // null for volumes
  std::vector<std::vector<Candidate>> candidates_;   // per job slot; only grows
  std::vector<Chunk> chunks_;
};

}  // namespace

std::unique_ptr<RayExecutor> make_cpu_executor(std::unique_ptr<MeshTracerFactory> tracers) {
  return std::make_unique<CpuExecutor>(std::move(tracers));
}

}  // namespace rtcd
