// The CPU executor: candidate selection, then every candidate ray of the
// batch traced or walked, parallel over jobs and over fixed chunks of rays
// with TBB. Each ray writes its own slot, so results never depend on the
// thread count, and buffers keep their capacity from step to step.
#include "rtcd/cpu_executor.hpp"

#include <algorithm>

#include "parallel.hpp"
#include "rtcd/error.hpp"
#include "rtcd/kernel/classify.h"
#include "rtcd/kernel/nearest.h"
#include "rtcd/kernel/volumes.h"
#include "rtcd/kernel/walk.h"

namespace rtcd {
namespace {

static_assert(sizeof(Eigen::Vector3f) == sizeof(rtcd_vec3), "positions are handed to the kernel as packed floats");
static_assert(sizeof(Mesh::Triangle) == 3 * sizeof(rtcd_uint) && sizeof(Mesh::Neighbors) == 3 * sizeof(rtcd_int));

rtcd_vec3 to_kernel(const Eigen::Vector3f& v) { return rtcd_v3(v.x(), v.y(), v.z()); }
rtcd_vec3 to_kernel(const Eigen::Vector3d& v) { return rtcd_v3(float(v.x()), float(v.y()), float(v.z())); }

// Most rays per parallel chunk, and the least rays worth handing to other threads:
// a traced ray costs tens of walks, so full batches go parallel far sooner.
constexpr size_t kChunk = 128;
constexpr size_t kParallelWalks = 8192;
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
    // Chunks small enough to spread even a one-pair step over the threads;
    // each ray writes its own slot, so the split never changes a result.
    size_t rays = 0;
    for (size_t j = 0; j < jobs.size(); ++j) rays += candidates_[j].size();
    const uint32_t chunk = uint32_t(std::clamp<size_t>(rays / 16, 16, kChunk));
    chunks_.clear();
    for (uint32_t j = 0; j < jobs.size(); ++j) {
      const uint32_t n = uint32_t(candidates_[j].size());
      for (uint32_t begin = 0; begin < n; begin += chunk) chunks_.push_back({j, begin, std::min<uint32_t>(n, begin + chunk)});
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
    int32_t start;  // iterative: the exit walk's first triangle
    int32_t entry;  // iterative: the entry walk's (TrackedRay::entry)
    rtcd_vec3 origin, direction;
  };
  struct Chunk {
    uint32_t job, begin, end;
  };

  void select(const RayJob& job, std::vector<Candidate>& out) const {
    out.clear();
    if (job.overlap.empty()) return;
    const RaySources& rs = shapes_[job.source]->sources();
    auto consider = [&](uint32_t vertex, int32_t start, int32_t entry) {
      if (rs.directions[vertex].isZero()) return;  // a vertex with no normal casts no ray
      const Eigen::Vector3d p = job.rotation * rs.origins[vertex].cast<double>() + job.translation;
      if (!job.overlap.contains(p)) return;
      out.push_back({vertex, start, entry, to_kernel(p), to_kernel(Eigen::Vector3d(job.rotation * rs.directions[vertex].cast<double>()))});
    };
    if (job.iterative) {
      for (const TrackedRay& r : job.tracked) consider(r.vertex, r.triangle, r.entry);
    } else {
      for (uint32_t v = 0; v < rs.origins.size(); ++v) consider(v, -1, -1);
    }
  }

  RayOutcome trace(const RayJob& job, const Candidate& c, const Config& config) const {
    RayOutcome o;
    o.vertex = c.vertex;
    const Shape& target = *shapes_[job.target];
    const float extension = float(job.limits.distance_extension);
    if (const Mesh* mesh = target.mesh()) {
      const auto normals = mesh->triangle_normals();
      if (job.iterative) {
        const rtcd_ray ray = rtcd_make_ray(c.origin, c.direction);
        auto walk = [&](int32_t start) {
          const rtcd_walk_result w =
              rtcd_walk(&ray, reinterpret_cast<const rtcd_vec3*>(mesh->positions().data()),
                        reinterpret_cast<const rtcd_uint*>(mesh->triangles().data()),
                        reinterpret_cast<const rtcd_int*>(mesh->neighbors().data()), mesh->zero_area().data(), start,
                        job.limits.max_walk_steps);
          o.walk_steps += w.steps;
          return w;
        };
        int32_t start = c.start;
        if (start < 0) {
          // Watched since the full step, its nearest triangle not looked up
          // yet: done now that the pair walks.
          o.nearest_query = 1;
          start = tracers_[job.target]->nearest(c.origin, float(job.limits.watch_reach(config.mode)));
          if (start < 0) return o;  // dropped: nothing within reach
        }
        const rtcd_walk_result exit = walk(start);
        o.status = uint8_t(exit.status);
        rtcd_walk_result entry{RTCD_LINE_MISS, -1, 0.0f, 0};
        if (exit.status == RTCD_LINE_HIT && c.entry >= 0) entry = walk(c.entry);
        // near = 0: a mesh's box is a weak bound on the distance to its
        // surface (a concave mesh's box holds most vertices near it), and
        // keeping every vertex in it walking cost 60% more per steady step
        // (rtcd_bench iterative/64) for no missed ray in the validation.
        const int kind = rtcd_walked_kind(exit.status, exit.t, entry.status, entry.t, config.predictive,
                                          watches(config), 0, extension);
        if (kind < 0) {
          o.retraced = 1;
          full_trace(*tracers_[job.target], normals, target.bounds(), c, job.limits, config, true, o);
          return o;
        }
        const bool located = exit.status == RTCD_LINE_HIT || exit.status == RTCD_LINE_BEHIND || exit.status == RTCD_LINE_FRONT;
        o.kind = uint8_t(kind);
        o.triangle = located ? exit.triangle : start;
        o.t = exit.t;
        if (kind == RTCD_RAY_PENETRATING) o.entry = entry.triangle;
        return o;
      }
      full_trace(*tracers_[job.target], normals, target.bounds(), c, job.limits, config, false, o);
      return o;
    }
    const auto& shape = target.geometry();
    const rtcd_volume_hit h =
        std::holds_alternative<Sphere>(shape)
            ? rtcd_sphere_line(c.origin, c.direction, float(std::get<Sphere>(shape).radius))
        : std::holds_alternative<Box>(shape)
            ? rtcd_box_line(c.origin, c.direction, to_kernel(std::get<Box>(shape).half_extents.cast<float>().eval()))
            : rtcd_halfspace_line(c.origin, c.direction);
    // The line test is exact: a candidate neither inside nor about to enter
    // is watched while it stays near, in full steps as in iterative ones.
    o.status = uint8_t(h.status);
    o.kind = uint8_t(rtcd_line_kind(h.status, h.t, config.predictive, watches(config),
                                    within_reach(target.bounds(), job.limits, config, c), extension));
    o.t = h.t;
    o.triangle = h.face;
    return o;
  }

  // Watching serves only later walks, which full mode never makes; it
  // belongs to the predictive logic and is off with it.
  static bool watches(const Config& config) { return config.predictive && config.mode != Mode::full; }

  // Whether a vertex is within the watch reach of the target's box: near
  // enough to enter before the pair is traced in full again.
  static bool within_reach(const Aabb& bounds, const PairLimits& limits, const Config& config, const Candidate& c) {
    return bounds.grown(limits.watch_reach(config.mode)).contains(Eigen::Vector3d(c.origin.x, c.origin.y, c.origin.z));
  }

  // Full tracing of one mesh ray: the inward ray; if it does not leave the
  // target, the predictive ray; if neither meets it and the vertex is within
  // reach of the target's box, it is watched. What serves only later walks
  // (the entry face of a penetrating ray, a watched vertex's nearest
  // triangle) is found when the pair walks (`walking`: a walk's re-trace),
  // so full steps of pairs that are traced in full again cost no more.
  static void full_trace(const MeshTracer& tracer, std::span<const Eigen::Vector3f> normals, const Aabb& bounds,
                         const Candidate& c, const PairLimits& limits, const Config& config, bool walking,
                         RayOutcome& o) {
    const float extension = float(limits.distance_extension);
    auto leaves_through = [&](int32_t tri) { return rtcd_dot(c.direction, to_kernel(normals[tri])) > 0.0f; };
    o.kind = RTCD_RAY_DROPPED;
    o.triangle = -1;
    o.t = 0.0f;
    // Inward ray: a first hit leaving the target means the origin is inside.
    const TraceHit in = tracer.first_hit(rtcd_make_ray(c.origin, c.direction), 3.0e38f);
    if (in.triangle >= 0 && leaves_through(in.triangle)) {
      o.kind = RTCD_RAY_PENETRATING;
      o.triangle = in.triangle;
      o.t = in.t;
      // Where the line entered, behind the vertex: the next walks check the
      // vertex is still past it.
      if (walking) {
        const TraceHit back = tracer.first_hit(rtcd_make_ray(c.origin, rtcd_neg(c.direction)), 3.0e38f);
        if (back.triangle >= 0 && !leaves_through(back.triangle)) o.entry = back.triangle;
      }
      return;
    }
    if (!config.predictive) return;
    // Predictive ray: outward, no further than distance_extension.
    const TraceHit out = tracer.first_hit(rtcd_make_ray(c.origin, rtcd_neg(c.direction)), extension);
    o.predictive_cast = 1;
    if (out.triangle >= 0 && leaves_through(out.triangle)) {
      o.kind = RTCD_RAY_PREDICTIVE;
      o.triangle = out.triangle;
      o.t = -out.t;
      return;
    }
    if (!watches(config) || !within_reach(bounds, limits, config, c)) return;
    if (!walking) {
      o.kind = RTCD_RAY_WATCHED;  // triangle -1: looked up if the pair walks
      return;
    }
    o.nearest_query = 1;
    const int32_t near = tracer.nearest(c.origin, float(limits.watch_reach(config.mode)));
    if (near >= 0) {
      o.kind = RTCD_RAY_WATCHED;
      o.triangle = near;
    }
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
