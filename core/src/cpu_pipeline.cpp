// The CPU narrow phase: pair state, equation 2.1, candidate selection, the
// walk and the predictive classification, parallel over pairs and rays with
// TBB. Backends plug in only their full tracer (MeshTracer).
#include "rtcd/cpu_pipeline.hpp"

#include <chrono>
#include <unordered_map>
#include <unordered_set>

#include <tbb/parallel_for.h>

#include "rtcd/criterion.hpp"
#include "rtcd/error.hpp"
#include "rtcd/kernel/classify.h"
#include "rtcd/kernel/volumes.h"
#include "rtcd/kernel/walk.h"

namespace rtcd {
namespace {

static_assert(sizeof(Eigen::Vector3f) == sizeof(rtcd_vec3), "positions are handed to the kernel as packed floats");
static_assert(sizeof(Mesh::Triangle) == 3 * sizeof(rtcd_uint) && sizeof(Mesh::Neighbors) == 3 * sizeof(rtcd_int));

rtcd_vec3 to_kernel(const Eigen::Vector3f& v) { return rtcd_v3(v.x(), v.y(), v.z()); }

using Clock = std::chrono::steady_clock;
double seconds_since(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

uint64_t pair_key(BodyId a, BodyId b) { return (uint64_t(std::min(a, b)) << 32) | std::max(a, b); }

// Rays per parallel chunk; fixed so results never depend on thread count.
constexpr size_t kChunk = 512;

struct TrackedRay {
  uint32_t vertex;
  int32_t triangle;
};

// One ray's outcome, in the target's local frame.
struct Outcome {
  uint32_t vertex;
  int32_t triangle;
  int kind;  // rtcd_ray_kind
  double t;
  Eigen::Vector3d origin, direction;
};

// Distance along the ray to where it leaves the target through the face the
// kernel chose, in double precision: depths then agree across backends (and
// with the exact reference) to far better than float. Mesh: the triangle's
// plane; box: the face's plane; sphere: the far root (where the line leaves);
// half-space: its plane.
double refined_distance(const Shape& target, int32_t face, const Eigen::Vector3d& origin,
                        const Eigen::Vector3d& direction) {
  if (const Mesh* mesh = target.mesh()) {
    const auto& tri = mesh->triangles()[face];
    const Eigen::Vector3d a = mesh->positions()[tri[0]].cast<double>();
    const Eigen::Vector3d n =
        (mesh->positions()[tri[1]].cast<double>() - a).cross(mesh->positions()[tri[2]].cast<double>() - a);
    return n.dot(a - origin) / n.dot(direction);
  }
  if (const auto* sphere = std::get_if<Sphere>(&target.geometry())) {
    const double a = direction.squaredNorm(), b = origin.dot(direction);
    const double c = origin.squaredNorm() - sphere->radius * sphere->radius;
    return (-b + std::sqrt(std::max(b * b - a * c, 0.0))) / a;
  }
  if (std::holds_alternative<HalfSpace>(target.geometry())) return -origin.z() / direction.z();
  const int axis = face / 2;
  const double plane = (face % 2 == 0 ? 1.0 : -1.0) * std::get<Box>(target.geometry()).half_extents[axis];
  return (plane - origin[axis]) / direction[axis];
}

struct JobStats {
  size_t candidates = 0, rays_full = 0, rays_predictive = 0, rays_iterative = 0, walk_steps = 0;
  std::array<size_t, RTCD_LINE_STATUS_COUNT> endings{};
  void add(const JobStats& o) {
    candidates += o.candidates;
    rays_full += o.rays_full;
    rays_predictive += o.rays_predictive;
    rays_iterative += o.rays_iterative;
    walk_steps += o.walk_steps;
    for (int i = 0; i < RTCD_LINE_STATUS_COUNT; ++i) endings[i] += o.endings[i];
  }
};

class CpuNarrowPhase final : public NarrowPhase {
 public:
  CpuNarrowPhase(std::string name, std::vector<std::string> devices, std::unique_ptr<MeshTracerFactory> tracers,
                 const Config& config)
      : NarrowPhase(config), name_(std::move(name)), devices_(std::move(devices)), tracers_(std::move(tracers)) {}

  std::string name() const override { return name_; }
  std::vector<std::string> devices() const override { return devices_; }

  ShapeId add_shape(std::shared_ptr<const Shape> shape) override {
    if (!shape) throw UsageError("add_shape: null shape");
    ShapeEntry e;
    if (const Mesh* m = shape->mesh()) e.tracer = tracers_->build(*m);
    e.shape = std::move(shape);
    shapes_.push_back(std::move(e));
    return ShapeId(shapes_.size() - 1);
  }

  BodyId add_body(ShapeId shape, const Pose& pose) override {
    if (shape >= shapes_.size()) throw UsageError("add_body: unknown shape " + std::to_string(shape));
    bodies_.push_back({shape, checked(pose), true});
    return BodyId(bodies_.size() - 1);
  }

  void remove_body(BodyId body) override {
    body_at(body).alive = false;
    std::erase_if(states_, [body](const auto& kv) {
      return BodyId(kv.first >> 32) == body || BodyId(kv.first & 0xffffffffu) == body;
    });
  }

  void set_pose(BodyId body, const Pose& pose) override { body_at(body).pose = checked(pose); }

  using NarrowPhase::detect;
  void detect(std::span<const BodyPair> pairs, StepResult& out) override;

 private:
  struct ShapeEntry {
    std::shared_ptr<const Shape> shape;
    std::unique_ptr<MeshTracer> tracer;  // meshes only
  };
  struct Body {
    ShapeId shape;
    Pose pose;
    bool alive;
  };
  struct PairState {
    Pose relative_at_full;               // lower id's frame in the higher id's frame
    std::vector<TrackedRay> tracked[2];  // [0]: lower id's rays into the higher, [1]: the reverse
  };
  // One direction of one pair.
  struct Job {
    size_t pair_index;
    BodyId source, target;
    bool iterative;
    std::vector<TrackedRay>* tracked;  // previous step's rays in, this step's out
    std::vector<Outcome> outcomes;
    JobStats stats;
  };

  Body& body_at(BodyId id) {
    if (id >= bodies_.size() || !bodies_[id].alive) throw UsageError("unknown body " + std::to_string(id));
    return bodies_[id];
  }

  void run(Job& job) const;
  Outcome trace_one(const Shape& target, const MeshTracer* tracer, uint32_t vertex, int32_t start,
                    rtcd_vec3 origin, rtcd_vec3 direction, bool iterative, JobStats& stats) const;
  void gather(const Job& job, StepResult& out, bool is_a) const;

  std::string name_;
  std::vector<std::string> devices_;
  std::unique_ptr<MeshTracerFactory> tracers_;
  std::vector<ShapeEntry> shapes_;
  std::vector<Body> bodies_;
  std::unordered_map<uint64_t, PairState> states_;
};

void CpuNarrowPhase::detect(std::span<const BodyPair> pairs, StepResult& out) {
  auto t0 = Clock::now();
  out.pairs.clear();
  out.contacts.clear();
  out.predictive.clear();
  out.stats = {};

  // Prepare: validate, evict absent pairs, choose full or iterative per pair.
  std::unordered_set<uint64_t> seen;
  for (const BodyPair& p : pairs) {
    body_at(p.a);
    body_at(p.b);
    if (p.a == p.b) throw UsageError("pair (" + std::to_string(p.a) + ", " + std::to_string(p.b) + ") is one body");
    if (!seen.insert(pair_key(p.a, p.b)).second)
      throw UsageError("pair (" + std::to_string(p.a) + ", " + std::to_string(p.b) + ") appears twice in one step");
  }
  std::erase_if(states_, [&](const auto& kv) { return !seen.contains(kv.first); });

  std::vector<Job> jobs;
  jobs.reserve(2 * pairs.size());
  out.pairs.resize(pairs.size());
  for (size_t i = 0; i < pairs.size(); ++i) {
    const BodyPair p = pairs[i];
    const BodyId lo = std::min(p.a, p.b), hi = std::max(p.a, p.b);
    const Pose relative = bodies_[hi].pose.inverse() * bodies_[lo].pose;
    auto [it, fresh] = states_.try_emplace(pair_key(lo, hi));
    PairState& state = it->second;
    bool iterative = false;
    if (!fresh && config_.mode == Mode::iterative) {
      iterative = true;
    } else if (!fresh && config_.mode == Mode::automatic) {
      const double radius = std::max(shapes_[bodies_[lo].shape].shape->radius(),
                                     shapes_[bodies_[hi].shape].shape->radius());
      iterative = max_displacement(state.relative_at_full, relative, radius) <= config_.displacement_threshold;
      if (!iterative) ++out.stats.fallbacks_to_full;
    }
    if (!iterative) {
      state.relative_at_full = relative;
      state.tracked[0].clear();
      state.tracked[1].clear();
    }
    out.pairs[i].pair = p;
    out.pairs[i].mode = iterative ? PairMode::iterative : PairMode::full;
    ++(iterative ? out.stats.pairs_iterative : out.stats.pairs_full);
    jobs.push_back({i, p.a, p.b, iterative, &state.tracked[p.a == lo ? 0 : 1], {}, {}});
    jobs.push_back({i, p.b, p.a, iterative, &state.tracked[p.b == lo ? 0 : 1], {}, {}});
  }
  out.stats.seconds_prepare = seconds_since(t0);

  for (bool iterative : {false, true}) {
    auto t = Clock::now();
    tbb::parallel_for(size_t(0), jobs.size(), [&](size_t j) {
      if (jobs[j].iterative == iterative) run(jobs[j]);
    });
    (iterative ? out.stats.seconds_iterative : out.stats.seconds_full) = seconds_since(t);
  }

  // Gather in input order: a's rays, then b's.
  auto t = Clock::now();
  JobStats total;
  for (size_t j = 0; j < jobs.size(); ++j) {
    PairResult& pr = out.pairs[jobs[j].pair_index];
    if (j % 2 == 0) {
      pr.first_contact = out.contacts.size();
      pr.first_predictive = out.predictive.size();
    }
    gather(jobs[j], out, j % 2 == 0);
    pr.contact_count = out.contacts.size() - pr.first_contact;
    pr.predictive_count = out.predictive.size() - pr.first_predictive;
    pr.colliding = pr.contact_count > 0;
    total.add(jobs[j].stats);
  }
  for (PairResult& pr : out.pairs)
    for (const Contact& c : out.contacts_of(pr)) pr.max_depth = std::max(pr.max_depth, c.depth);
  out.stats.candidates = total.candidates;
  out.stats.rays_full = total.rays_full;
  out.stats.rays_predictive = total.rays_predictive;
  out.stats.rays_iterative = total.rays_iterative;
  out.stats.walk_steps = total.walk_steps;
  out.stats.walk_endings = total.endings;
  out.stats.seconds_gather = seconds_since(t);
}

void CpuNarrowPhase::run(Job& job) const {
  const Body& src = bodies_[job.source];
  const Body& dst = bodies_[job.target];
  const Shape& source = *shapes_[src.shape].shape;
  const ShapeEntry& target = shapes_[dst.shape];
  // Everything is traced in the target's local frame: its acceleration
  // structure never moves, and far from the world origin the relative
  // transform keeps the precision that world coordinates would lose.
  const Pose to_target = dst.pose.inverse() * src.pose;
  const Aabb overlap = target.shape->bounds()
                           .intersection(source.bounds().transformed(to_target))
                           .grown(config_.distance_extension);
  const RaySources& rs = source.sources();
  const Eigen::Matrix3d rotation = to_target.orientation.toRotationMatrix();

  // Candidate rays: all origins in a full step, last step's tracked rays in an iterative one.
  if (overlap.empty()) {
    job.tracked->clear();
    return;
  }
  const size_t count = job.iterative ? job.tracked->size() : rs.origins.size();
  const size_t chunks = (count + kChunk - 1) / kChunk;
  std::vector<std::vector<Outcome>> per_chunk(chunks);
  std::vector<JobStats> chunk_stats(chunks);
  tbb::parallel_for(size_t(0), chunks, [&](size_t c) {
    for (size_t k = c * kChunk; k < std::min(count, (c + 1) * kChunk); ++k) {
      const uint32_t vertex = job.iterative ? (*job.tracked)[k].vertex : uint32_t(k);
      const int32_t start = job.iterative ? (*job.tracked)[k].triangle : -1;
      if (rs.directions[vertex].isZero()) continue;  // a vertex with no normal casts no ray
      const Eigen::Vector3d p = rotation * rs.origins[vertex].cast<double>() + to_target.position;
      if (!overlap.contains(p)) continue;
      ++chunk_stats[c].candidates;
      const Eigen::Vector3d d = rotation * rs.directions[vertex].cast<double>();
      Outcome o = trace_one(*target.shape, target.tracer.get(), vertex, start,
                            rtcd_v3(float(p.x()), float(p.y()), float(p.z())),
                            rtcd_v3(float(d.x()), float(d.y()), float(d.z())), job.iterative, chunk_stats[c]);
      if (o.kind == RTCD_RAY_DROPPED) continue;
      o.origin = p;
      o.direction = d;
      // Keep the kernel's decision; only sharpen the distance.
      const double t = refined_distance(*target.shape, o.triangle, p, d);
      o.t = o.kind == RTCD_RAY_PENETRATING ? std::max(t, 0.0) : std::min(t, 0.0);
      per_chunk[c].push_back(o);
    }
  });
  job.tracked->clear();
  for (size_t c = 0; c < chunks; ++c) {
    job.stats.add(chunk_stats[c]);
    for (const Outcome& o : per_chunk[c]) {
      job.outcomes.push_back(o);
      job.tracked->push_back({o.vertex, o.triangle});
    }
  }
}

Outcome CpuNarrowPhase::trace_one(const Shape& target, const MeshTracer* tracer, uint32_t vertex, int32_t start,
                                  rtcd_vec3 origin, rtcd_vec3 direction, bool iterative, JobStats& stats) const {
  Outcome o{vertex, -1, RTCD_RAY_DROPPED, 0.0, {}, {}};
  const float extension = float(config_.distance_extension);
  int status = RTCD_LINE_MISS;
  float t = 0.0f;
  if (const Mesh* mesh = target.mesh()) {
    const auto normals = mesh->triangle_normals();
    auto leaves_through = [&](int32_t tri) { return rtcd_dot(direction, to_kernel(normals[tri])) > 0.0f; };
    if (iterative) {
      const rtcd_ray ray = rtcd_make_ray(origin, direction);
      const rtcd_walk_result w =
          rtcd_walk(&ray, reinterpret_cast<const rtcd_vec3*>(mesh->positions().data()),
                    reinterpret_cast<const rtcd_uint*>(mesh->triangles().data()),
                    reinterpret_cast<const rtcd_int*>(mesh->neighbors().data()), mesh->zero_area().data(), start,
                    config_.max_walk_steps);
      status = w.status;
      t = w.t;
      o.triangle = w.triangle;
      ++stats.rays_iterative;
      stats.walk_steps += w.steps;
      ++stats.endings[status];
    } else {
      // Inward ray: a first hit leaving the target means the origin is inside.
      const TraceHit in = tracer->first_hit(rtcd_make_ray(origin, direction), 3.0e38f);
      ++stats.rays_full;
      if (in.triangle >= 0 && leaves_through(in.triangle)) {
        status = RTCD_LINE_HIT;
        t = in.t;
        o.triangle = in.triangle;
      } else if (config_.predictive) {
        // Predictive ray: outward, no further than distance_extension.
        const TraceHit out = tracer->first_hit(rtcd_make_ray(origin, rtcd_neg(direction)), extension);
        ++stats.rays_predictive;
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
        std::holds_alternative<Sphere>(shape) ? rtcd_sphere_line(origin, direction, float(std::get<Sphere>(shape).radius))
        : std::holds_alternative<Box>(shape)
            ? rtcd_box_line(origin, direction, to_kernel(std::get<Box>(shape).half_extents.cast<float>()))
            : rtcd_halfspace_line(origin, direction);
    ++(iterative ? stats.rays_iterative : stats.rays_full);
    if (iterative) ++stats.endings[h.status];
    status = h.status;
    t = h.t;
    o.triangle = h.face;
  }
  o.kind = rtcd_classify(status, t, config_.predictive, extension);
  o.t = t;
  return o;
}

void CpuNarrowPhase::gather(const Job& job, StepResult& out, bool is_a) const {
  const Body& src = bodies_[job.source];
  const Body& dst = bodies_[job.target];
  const Shape& source = *shapes_[src.shape].shape;
  const Shape& target = *shapes_[dst.shape].shape;
  for (const Outcome& o : job.outcomes) {
    // Outward unit normal at the exit point, in the target's local frame.
    Eigen::Vector3d local_normal;
    if (const Mesh* m = target.mesh()) {
      local_normal = m->triangle_normals()[o.triangle].cast<double>();
    } else if (std::holds_alternative<Sphere>(target.geometry())) {
      local_normal = (o.origin + o.t * o.direction).normalized();
    } else if (std::holds_alternative<HalfSpace>(target.geometry())) {
      local_normal = Eigen::Vector3d::UnitZ();
    } else {
      local_normal = Eigen::Vector3d::Zero();
      local_normal[o.triangle / 2] = o.triangle % 2 == 0 ? 1.0 : -1.0;
    }
    RayRecord r;
    r.source = is_a ? Side::a : Side::b;
    r.source_body = job.source;
    r.target_body = job.target;
    r.vertex = o.vertex;
    r.triangle = o.triangle;
    r.origin = src.pose.apply(source.sources().origins[o.vertex].cast<double>());
    r.direction = (src.pose.orientation * source.sources().directions[o.vertex].cast<double>()).normalized();
    r.normal = (dst.pose.orientation * local_normal).normalized();
    if (o.kind == RTCD_RAY_PENETRATING) {
      Contact c;
      static_cast<RayRecord&>(c) = r;
      c.depth = o.t;
      c.projected_depth = c.depth * std::abs(r.direction.dot(r.normal));
      c.push = config_.projected ? Eigen::Vector3d(r.normal * c.projected_depth) : Eigen::Vector3d(r.direction * c.depth);
      out.contacts.push_back(c);
    } else {
      PredictiveRay p;
      static_cast<RayRecord&>(p) = r;
      p.distance = -o.t;
      out.predictive.push_back(p);
    }
  }
}

}  // namespace

std::unique_ptr<NarrowPhase> make_cpu_narrow_phase(std::string name, std::vector<std::string> devices,
                                                   std::unique_ptr<MeshTracerFactory> tracers,
                                                   const Config& config) {
  return std::make_unique<CpuNarrowPhase>(std::move(name), std::move(devices), std::move(tracers), config);
}

}  // namespace rtcd
