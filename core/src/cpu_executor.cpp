// The CPU executor: candidate selection, then every candidate ray of the
// batch traced or walked, parallel over jobs and over fixed chunks of rays
// with TBB. Each ray writes its own slot, so results never depend on the
// thread count, and buffers keep their capacity from step to step.
#include "rtcd/cpu_executor.hpp"

#include <algorithm>
#include <bit>
#include <cmath>
#include <limits>

#include "parallel.hpp"
#include "rtcd/error.hpp"
#include "rtcd/kernel/brute.h"
#include "rtcd/kernel/fold.h"
#include "rtcd/kernel/nearest.h"
#include "rtcd/kernel/walk.h"

// The CPU side of the tracer that kernel/trace.h calls: a MeshTracer and its mesh.
struct rtcd_tracer {
  const rtcd::MeshTracer* tracer;
  const rtcd::Mesh* mesh;
};
// The distance of a hit as the shared locate code measures it (what the
// brute force and the device report), so a tracer's own arithmetic (Embree's
// differs between instruction sets) reaches no result; the tracer's own
// where the watertight test puts the line just outside the triangle.
static rtcd_hit rtcd_tracer_first_hit(const rtcd_tracer* t, const rtcd_ray* ray, float t_max) {
  const rtcd::TraceHit h = t->tracer->first_hit(*ray, t_max);
  if (h.triangle < 0) return {h.triangle, h.t};
  const auto& tri = t->mesh->triangles()[size_t(h.triangle)];
  const auto corner = [&](int k) {
    const Eigen::Vector3f& v = t->mesh->positions()[tri[k]];
    return rtcd_v3(v.x(), v.y(), v.z());
  };
  const float located = rtcd_hit_distance(ray, corner(0), corner(1), corner(2));
  return {h.triangle, located >= 0.0f && located <= t_max ? located : h.t};
}
static rtcd_int rtcd_tracer_nearest(const rtcd_tracer* t, rtcd_vec3 point, float radius, float enough) {
  return t->tracer->nearest(point, radius, enough);
}
static rtcd_walk_result rtcd_tracer_walk(const rtcd_tracer* t, const rtcd_ray* ray, rtcd_int start, rtcd_uint max_steps) {
  const rtcd::Mesh& m = *t->mesh;
  return rtcd_walk(ray, reinterpret_cast<const rtcd_vec3*>(m.positions().data()),
                   reinterpret_cast<const rtcd_uint*>(m.triangles().data()),
                   reinterpret_cast<const rtcd_int*>(m.neighbors().data()), m.zero_area().data(), start, max_steps);
}
static int rtcd_tracer_leaves(const rtcd_tracer* t, rtcd_int triangle, rtcd_vec3 direction) {
  const Eigen::Vector3f& n = t->mesh->triangle_normals()[size_t(triangle)];
  return rtcd_dot(direction, rtcd_v3(n.x(), n.y(), n.z())) > 0.0f;
}
static int rtcd_tracer_fold_free(const rtcd_tracer* t, rtcd_int face, rtcd_vec3 origin, rtcd_vec3 toward,
                                 float reach) {
  const rtcd::Mesh& m = *t->mesh;
  const rtcd::Mesh::FoldGuard& g = m.fold_guard();
  return rtcd_fold_free(face, origin, toward, reach, reinterpret_cast<const rtcd_vec3*>(m.triangle_normals().data()),
                        reinterpret_cast<const rtcd_fold_face*>(g.faces.data()), g.ring_first.data(), g.ring.data());
}

static float rtcd_tracer_distance2(const rtcd_tracer* t, rtcd_int triangle, rtcd_vec3 point) {
  const rtcd::Mesh& m = *t->mesh;
  const auto& tri = m.triangles()[size_t(triangle)];
  const auto corner = [&](int k) {
    const Eigen::Vector3f& v = m.positions()[tri[k]];
    return rtcd_v3(v.x(), v.y(), v.z());
  };
  return rtcd_point_triangle_distance2(point, corner(0), corner(1), corner(2));
}

#include "rtcd/kernel/trace.h"

namespace rtcd {
namespace {

static_assert(sizeof(Eigen::Vector3f) == sizeof(rtcd_vec3), "positions are handed to the kernel as packed floats");
static_assert(sizeof(Mesh::Triangle) == 3 * sizeof(rtcd_uint) && sizeof(Mesh::Neighbors) == 3 * sizeof(rtcd_int));
static_assert(sizeof(Mesh::FoldGuard::Face) == sizeof(rtcd_fold_face));

rtcd_vec3 to_kernel(const Eigen::Vector3f& v) { return rtcd_v3(v.x(), v.y(), v.z()); }

// Most rays per parallel chunk; the least items (tracked rays to walk, or
// source vertices to select from) worth spreading jobs over threads; the
// least traced rays worth it (a traced ray costs tens of walks).
constexpr size_t kChunk = 128;
constexpr size_t kParallelItems = 512;
constexpr size_t kParallelTraces = 64;
// Full jobs selected per parallel task, which keeps its own vertex marks;
// the least blocks of a batch that trace their rays as they select them
// (fewer are split into chunks of rays).
constexpr size_t kJobsPerBlock = 16;
constexpr size_t kTracedBlocks = 8;

class CpuExecutor final : public RayExecutor {
 public:
  explicit CpuExecutor(std::unique_ptr<MeshTracerFactory> tracers) : factory_(std::move(tracers)) {}

  void add_shape(std::shared_ptr<const Shape> shape, const ShapeScale&) override {
    const Mesh* mesh = shape->mesh();
    tracers_.push_back(mesh ? factory_->build(*mesh) : nullptr);
    shapes_.push_back(std::move(shape));
  }

  void configure(const Config& config) override { config_ = config; }

  void execute(RayBatch& batch) override {
    const std::span<const RayJob> jobs = batch.jobs;
    const std::span<std::vector<RayOutcome>> outcomes = batch.outcomes;
    const std::span<RayTally> tallies = batch.tallies;
    const Config& config = config_;
    if (candidates_.size() < jobs.size()) candidates_.resize(jobs.size());
    if (params_.size() < jobs.size()) params_.resize(jobs.size());
    size_t work = 0;
    for (const RayJob& job : jobs) work += job.iterative ? job.tracked.size() : shapes_[job.source]->sources().item_count();
    if (batch.iterative) {
      // Walks are short and even: one pass per job, each tracked ray placed
      // and walked at once.
      for_each_index(jobs.size(), work >= kParallelItems, [&](size_t j) {
        params_[j] = make_trace_params(jobs[j], *shapes_[jobs[j].source], *shapes_[jobs[j].target], config);
        outcomes[j].clear();
        for_each_tracked(jobs[j], params_[j], [&](const rtcd_candidate& c) { trace(jobs[j], params_[j], c, outcomes[j].emplace_back()); });
        tallies[j] = settle_outcomes(outcomes[j], true);
      });
      return;  // the rays run where they are
    }
    // Full jobs select their candidates in fixed blocks of jobs, each block
    // with its own marks, kept across steps. With enough blocks to keep
    // every thread busy, each candidate is traced as soon as it is selected,
    // so no candidate list leaves the cache; fewer jobs, whose rays cost far
    // more than their selection and vary, list their candidates first and
    // spread the rays over threads in chunks.
    const size_t blocks = (jobs.size() + kJobsPerBlock - 1) / kJobsPerBlock;
    if (marks_.size() < blocks) marks_.resize(blocks);
    const bool at_once = blocks >= kTracedBlocks;
    for_each_index(blocks, work >= kParallelItems, [&](size_t b) {
      for (size_t j = b * kJobsPerBlock; j < std::min(jobs.size(), (b + 1) * kJobsPerBlock); ++j) {
        params_[j] = make_trace_params(jobs[j], *shapes_[jobs[j].source], *shapes_[jobs[j].target], config);
        outcomes[j].clear();
        candidates_[j].clear();
        for_each_selected(jobs[j], params_[j], marks_[b], [&](const rtcd_candidate& c) {
          if (at_once) {
            trace(jobs[j], params_[j], c, outcomes[j].emplace_back());
          } else {
            candidates_[j].push_back(c);
          }
        });
        if (at_once) {
          tallies[j] = settle_outcomes(outcomes[j], false);
        } else {
          outcomes[j].resize(candidates_[j].size());
        }
      }
    });
    if (at_once) return;
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
      for (uint32_t k = chunk.begin; k < chunk.end; ++k)
        trace(jobs[chunk.job], params_[chunk.job], candidates_[chunk.job][k], outcomes[chunk.job][k]);
    });
    for (size_t j = 0; j < jobs.size(); ++j) tallies[j] = settle_outcomes(outcomes[j], false);
  }

 private:
  struct Chunk {
    uint32_t job, begin, end;
  };

  // A candidate placed in the target's frame (rtcd_place_item), handed to
  // `take`; none where the item is outside the job's overlap box.
  template <class Take>
  static void place(const RaySources& rs, const rtcd_frame& frame, const rtcd_trace_params& params, uint32_t item,
                    int32_t start, int32_t entry, const Take& take) {
    rtcd_candidate c{item, start, entry, 0, {}, {}};
    if (rtcd_place_item(&frame, &params, item, to_kernel(rs.item_origin(item)), to_kernel(rs.item_direction(item)),
                        &c.origin, &c.direction))
      take(c);
  }

  // An iterative job's candidates: its tracked rays, in tracked order.
  template <class Take>
  void for_each_tracked(const RayJob& job, const rtcd_trace_params& params, const Take& take) const {
    if (job.overlap.empty()) return;
    const RaySources& rs = shapes_[job.source]->sources();
    const rtcd_frame frame = make_frame(job);
    for (const RayOutcome& r : job.tracked) place(rs, frame, params, r.vertex, r.triangle, r.entry, take);
  }

  // A full job's candidates, in item order: the items near the overlap box
  // (visit_near_items), which `marks` put back in item order, then the
  // exact placement decides.
  template <class Take>
  void for_each_selected(const RayJob& job, const rtcd_trace_params& params, std::vector<uint64_t>& marks,
                         const Take& take) const {
    if (job.overlap.empty()) return;
    const RaySources& rs = shapes_[job.source]->sources();
    const rtcd_frame frame = make_frame(job);
    marks.assign((rs.item_count() + 63) / 64, 0);
    visit_near_items(frame, rs, shapes_[job.target]->distance_bound(), edge_reach(params),
                     [&](uint32_t v) { marks[v / 64] |= uint64_t(1) << (v % 64); });
    for (size_t w = 0; w < marks.size(); ++w)
      for (uint64_t bits = marks[w]; bits != 0; bits &= bits - 1)
        place(rs, frame, params, uint32_t(64 * w + std::countr_zero(bits)), -1, -1, take);
  }

  void trace(const RayJob& job, const rtcd_trace_params& params, const rtcd_candidate& c, RayOutcome& o) const {
    rtcd_outcome_init(&o, c.vertex);
    const Shape& target = *shapes_[job.target];
    if (const Mesh* mesh = target.mesh()) {
      const rtcd_tracer tracer{tracers_[job.target].get(), mesh};
      if (rtcd_item_kind(RTCD_TARGET_MESH, &params, c.vertex) != RTCD_ITEM_ORIGIN) {
        rtcd_edge_trace(&tracer, &params, &c, &o);
      } else if (job.iterative) {
        rtcd_walk_trace(&tracer, &params, &c, &o);
      } else {
        rtcd_full_trace(&tracer, &params, &c, 0, &o);
      }
    } else {
      const auto& shape = target.geometry();
      int kind = RTCD_TARGET_HALFSPACE;
      float radius = 0.0f;
      rtcd_vec3 half = rtcd_v3(0, 0, 0);
      if (const auto* sphere = std::get_if<Sphere>(&shape)) {
        kind = RTCD_TARGET_SPHERE;
        radius = float(sphere->radius);
      } else if (const auto* box = std::get_if<Box>(&shape)) {
        kind = RTCD_TARGET_BOX;
        half = to_kernel(box->half_extents.cast<float>().eval());
      }
      const int item = rtcd_item_kind(kind, &params, c.vertex);
      if (item == RTCD_ITEM_SPHERE) {
        rtcd_sphere_trace(kind, radius, half, &params, &c, &o);
      } else if (item == RTCD_ITEM_EDGE) {
        rtcd_edge_volume_trace(kind, radius, half, &params, &c, &o);
      } else {
        rtcd_volume_trace(kind, radius, half, &params, &c, &o);
      }
    }
  }

  std::unique_ptr<MeshTracerFactory> factory_;
  Config config_;
  std::vector<std::shared_ptr<const Shape>> shapes_;
  std::vector<std::unique_ptr<MeshTracer>> tracers_;    // null for volumes
  std::vector<std::vector<rtcd_candidate>> candidates_;  // per job slot; only grows
  std::vector<rtcd_trace_params> params_;                // per job slot
  std::vector<Chunk> chunks_;
  std::vector<std::vector<uint64_t>> marks_;  // per block of full jobs: the vertices selected
};

}  // namespace

std::unique_ptr<RayExecutor> make_cpu_executor(std::unique_ptr<MeshTracerFactory> tracers) {
  return std::make_unique<CpuExecutor>(std::move(tracers));
}

rtcd_shape_traits shape_traits(const Shape& shape) {
  rtcd_shape_traits t;
  const Mesh* mesh = shape.mesh();
  t.kind = mesh                                             ? RTCD_TARGET_MESH
           : std::holds_alternative<Sphere>(shape.geometry()) ? RTCD_TARGET_SPHERE
           : std::holds_alternative<Box>(shape.geometry())    ? RTCD_TARGET_BOX
                                                              : RTCD_TARGET_HALFSPACE;
  t.convex = mesh && mesh->convex();
  t.first_edge = shape.sources().first_edge();
  t.sphere_radius = shape.sources().sphere_radius;
  return t;
}

rtcd_uint config_flags(const Config& config) {
  return (config.predictive ? RTCD_CONFIG_PREDICTIVE : 0u) |
         (config.predictive && config.mode != Mode::full ? RTCD_CONFIG_WATCH : 0u) |
         (config.verify_walks ? RTCD_CONFIG_VERIFY : 0u) | (config.edge_contacts ? RTCD_CONFIG_EDGES : 0u) |
         (config.nearest_surface ? RTCD_CONFIG_NEAREST : 0u) | (config.mode == Mode::automatic ? RTCD_CONFIG_AUTOMATIC : 0u);
}

rtcd_job_setup job_setup(const RayJob& job, const Config& config) {
  rtcd_job_setup s{};
  s.extension = job.limits.distance_extension;
  s.reach = job.limits.watch_reach(config.mode);
  s.moved = rtcd_float_at_least(job.moved);
  s.source_body = job.source_body;
  s.target_body = job.target_body;
  s.source = job.source;
  s.target = job.target;
  s.max_walk_steps = job.limits.max_walk_steps;
  s.flags = (job.iterative ? RTCD_JOB_ITERATIVE : 0u) | (job.edges ? RTCD_JOB_EDGES : 0u);
  return s;
}

rtcd_trace_params make_trace_params(const RayJob& job, const Shape& source, const Shape& target, const Config& config) {
  const rtcd_job_setup setup = job_setup(job, config);
  const rtcd_shape_traits source_traits = shape_traits(source), target_traits = shape_traits(target);
  const rtcd_box target_bounds = to_kernel(target.bounds());
  return rtcd_make_params(config_flags(config), &setup, &source_traits, &target_traits, &target_bounds);
}

rtcd_frame make_frame(const RayJob& job) {
  rtcd_frame f;
  for (int i = 0; i < 3; ++i) {
    for (int k = 0; k < 3; ++k) f.rotation[3 * i + k] = job.rotation(i, k);
    f.translation[i] = job.translation[i];
    f.lo[i] = job.overlap.min[i];
    f.hi[i] = job.overlap.max[i];
  }
  return f;
}

}  // namespace rtcd
