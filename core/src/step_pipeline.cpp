// The host side of every step, whatever executes the rays: validate the
// pairs, keep each pair's state (equation 2.1, the tracked rays), build the
// pair-directions, then turn the executor's outcomes into contacts,
// predictive rays, pair summaries and statistics. Every buffer keeps its
// capacity across steps, so a steady step allocates nothing.
#include "rtcd/step_pipeline.hpp"

#include <algorithm>
#include <chrono>
#include <condition_variable>
#include <exception>
#include <limits>
#include <mutex>
#include <optional>
#include <thread>
#include <utility>

#include <tbb/task_arena.h>

#include "parallel.hpp"
#include "rtcd/clock.hpp"
#include "rtcd/criterion.hpp"
#include "rtcd/distance_bound.hpp"
#include "rtcd/error.hpp"
#include "rtcd/kernel/classify.h"

namespace rtcd {
namespace {

std::string pair_text(BodyId a, BodyId b) { return "pair (" + std::to_string(a) + ", " + std::to_string(b) + ")"; }

// Least pairs worth placing (transforms and boxes) on several threads; least
// kept outcomes worth turning into records (dozens of flops each) on several.
constexpr size_t kParallelPairs = 1024;
constexpr size_t kParallelFill = 1024;
// Least steps a certificate must last at the pair's current speed.
constexpr double kCertificateSteps = 4.0;

// A shape as the host builds records from it: what the refinement and the
// records need, converted to double once instead of at every ray.
struct ShapeEntry {
  std::shared_ptr<const Shape> shape;
  std::vector<Eigen::Vector3d> directions;  // unit ray directions (zero where a vertex has no normal)
  std::vector<Eigen::Vector3d> normals;     // meshes: unit outward normal per triangle
  struct Plane {
    Eigen::Vector3d normal, point;  // meshes: (v1 - v0) x (v2 - v0) and v0, per triangle
  };
  std::vector<Plane> planes;
  ShapeScale scale;  // measured only when some limit is derived
  float longest_edge = 0.0f;  // meshes: which of a pair tests its edges (Config::edges_both_sides off)

  ShapeEntry(std::shared_ptr<const Shape> s, bool measure) : shape(std::move(s)) {
    if (measure) scale = measure_scale(*shape);
    const RaySources& rs = shape->sources();
    for (uint32_t e = rs.first_edge(); shape->mesh() && e < rs.item_count(); ++e)
      longest_edge = std::max(longest_edge, rs.item_direction(e).norm());
    for (const Eigen::Vector3f& d : shape->sources().directions)
      directions.push_back(d.isZero() ? Eigen::Vector3d::Zero() : Eigen::Vector3d(d.cast<double>().normalized()));
    if (const Mesh* m = shape->mesh()) {
      for (size_t i = 0; i < m->triangle_count(); ++i) {
        const auto& tri = m->triangles()[i];
        const Eigen::Vector3d a = m->positions()[tri[0]].cast<double>();
        planes.push_back({(m->positions()[tri[1]].cast<double>() - a).cross(m->positions()[tri[2]].cast<double>() - a), a});
        const Eigen::Vector3d n = m->triangle_normals()[i].cast<double>();
        normals.push_back(n.isZero() ? n : n.normalized());
      }
    }
  }

  // Distance along the ray to where it leaves this shape through the face
  // the executor chose, in double precision: depths then agree across
  // backends (and with the exact reference) to far better than float. Mesh:
  // the triangle's plane; box: the face's plane; sphere: the far root (where
  // the line leaves); half-space: its plane.
  double exit_distance(int32_t face, const Eigen::Vector3d& origin, const Eigen::Vector3d& direction) const {
    if (!planes.empty()) {
      const Plane& plane = planes[face];
      return plane.normal.dot(plane.point - origin) / plane.normal.dot(direction);
    }
    if (const auto* sphere = std::get_if<Sphere>(&shape->geometry())) {
      const double a = direction.squaredNorm(), b = origin.dot(direction);
      const double c = origin.squaredNorm() - sphere->radius * sphere->radius;
      return (-b + std::sqrt(std::max(b * b - a * c, 0.0))) / a;
    }
    if (std::holds_alternative<HalfSpace>(shape->geometry())) return -origin.z() / direction.z();
    const int axis = face / 2;
    const double plane = (face % 2 == 0 ? 1.0 : -1.0) * std::get<Box>(shape->geometry()).half_extents[axis];
    return (plane - origin[axis]) / direction[axis];
  }

  // Outward unit normal of the face a ray leaves through, in this shape's
  // frame; `exit` is where it leaves.
  Eigen::Vector3d exit_normal(int32_t face, const Eigen::Vector3d& exit) const {
    if (!normals.empty()) return normals[face];
    if (std::holds_alternative<Sphere>(shape->geometry())) return exit.normalized();
    if (std::holds_alternative<HalfSpace>(shape->geometry())) return Eigen::Vector3d::UnitZ();
    Eigen::Vector3d n = Eigen::Vector3d::Zero();
    n[face / 2] = face % 2 == 0 ? 1.0 : -1.0;
    return n;
  }

  // The face nearest to p, a point inside: for a mesh the executor finds it
  // (RayOutcome::nearest), and `exit` (the face the ray left through) stands
  // in; a box's face with the least room; a sphere's or a half-space's one.
  int32_t nearest_face(int32_t exit, const Eigen::Vector3d& p) const {
    const auto* box = std::get_if<Box>(&shape->geometry());
    if (!box) return exit;
    int32_t best = exit;
    double room = std::numeric_limits<double>::infinity();
    for (int32_t face = 0; face < 6; ++face) {
      const double r = box->half_extents[face / 2] - (face % 2 == 0 ? p[face / 2] : -p[face / 2]);
      if (r < room) room = r, best = face;
    }
    return best;
  }

  // The point of face `face` nearest to p (this shape's frame), in double:
  // an edge contact's way out. Mesh: the triangle's closest point; box: p
  // moved onto the face's plane; sphere: p pushed out along its radius.
  Eigen::Vector3d nearest_on_face(int32_t face, const Eigen::Vector3d& p) const {
    if (const Mesh* m = shape->mesh()) {
      const auto& tri = m->triangles()[size_t(face)];
      return closest_on_triangle(p, m->positions()[tri[0]].cast<double>(), m->positions()[tri[1]].cast<double>(),
                                 m->positions()[tri[2]].cast<double>());
    }
    if (const auto* sphere = std::get_if<Sphere>(&shape->geometry()))
      return p.isZero() ? Eigen::Vector3d(0, 0, sphere->radius) : Eigen::Vector3d(p.normalized() * sphere->radius);
    if (std::holds_alternative<HalfSpace>(shape->geometry())) return {p.x(), p.y(), 0.0};
    Eigen::Vector3d q = p;
    q[face / 2] = (face % 2 == 0 ? 1.0 : -1.0) * std::get<Box>(shape->geometry()).half_extents[face / 2];
    return q;
  }
};

class PipelineNarrowPhase final : public NarrowPhase {
 public:
  PipelineNarrowPhase(std::string name, std::vector<std::string> devices, std::unique_ptr<RayExecutor> executor,
                      const Config& config, int threads)
      : NarrowPhase(config),
        name_(std::move(name)),
        devices_(std::move(devices)),
        executor_(std::move(executor)),
        derive_(derives_limits(config_)),
        limit_settings_(limit_settings(config_)) {
    if (threads > 0) arena_.emplace(threads);
    executor_->configure(config_);
  }

  std::string name() const override { return name_; }
  std::vector<std::string> devices() const override { return devices_; }

  ~PipelineNarrowPhase() override {
    if (!worker_.joinable()) return;
    {
      std::unique_lock lock(mutex_);
      changed_.wait(lock, [&] { return !running_; });
      quit_ = true;
    }
    changed_.notify_all();
    worker_.join();
  }

  ShapeId add_shape(std::shared_ptr<const Shape> shape) override {
    idle("add_shape");
    if (!shape) throw UsageError("add_shape: null shape");
    ShapeEntry entry(std::move(shape), derive_);
    in_arena([&] { executor_->add_shape(entry.shape, entry.scale); });
    shapes_.push_back(std::move(entry));
    return ShapeId(shapes_.size() - 1);
  }

  BodyId add_body(ShapeId shape, const Pose& pose) override {
    idle("add_body");
    if (shape >= shapes_.size()) throw UsageError("add_body: unknown shape " + std::to_string(shape));
    bodies_.push_back({shape, checked(pose), true, {}, 0});
    poses_.push_back(to_kernel(bodies_.back().pose));
    executor_->add_body(shape);
    return BodyId(bodies_.size() - 1);
  }

  void remove_body(BodyId body) override {
    idle("remove_body");
    body_at(body).alive = false;
    size_t kept = 0;
    for (size_t k = 0; k < state_keys_.size(); ++k) {
      const uint64_t key = state_keys_[k];
      if (const BodyPair p = pair_of_key(key); p.a == body || p.b == body) continue;
      state_keys_[kept] = key;
      if (kept != k) states_[kept] = std::move(states_[k]);
      ++kept;
    }
    state_keys_.resize(kept);
    states_.resize(kept);
  }

  void set_pose(BodyId body, const Pose& pose) override {
    idle("set_pose");
    body_at(body).pose = checked(pose);
    poses_[body] = to_kernel(body_at(body).pose);
  }

  using NarrowPhase::detect;
  void detect(std::span<const BodyPair> pairs, StepResult& out) override {
    idle("detect");
    validate(pairs);  // before anything changes: bad input loses no state
    in_arena([&] { step(pairs, out); });
  }

  void detect_begin(std::span<const BodyPair> pairs, StepResult& out) override {
    idle("detect_begin");
    validate(pairs);
    if (!worker_.joinable()) worker_ = std::thread([this] { work(); });
    {
      std::lock_guard lock(mutex_);
      begun_ = {pairs, &out};
      running_ = true;
      error_ = nullptr;
    }
    busy_ = true;
    changed_.notify_all();
  }

  bool detect_done() const override {
    if (!busy_) throw UsageError("detect_done: no step begun");
    std::lock_guard lock(mutex_);
    return !running_;
  }

  void detect_end() override {
    if (!busy_) throw UsageError("detect_end: no step begun");
    std::exception_ptr error;
    {
      std::unique_lock lock(mutex_);
      changed_.wait(lock, [&] { return !running_; });
      std::swap(error, error_);
    }
    busy_ = false;
    if (error) std::rethrow_exception(error);
  }

 private:
  // Runs `work` in the narrow phase's own arena, if it has one.
  template <class Work>
  void in_arena(const Work& work) {
    if (arena_)
      arena_->execute(work);
    else
      work();
  }
  void step(std::span<const BodyPair> pairs, StepResult& out);
  // Throws when a begun step has not ended: the narrow phase is the step's.
  void idle(const char* call) const {
    if (busy_) throw UsageError(std::string(call) + ": a step begun with detect_begin is running; call detect_end first");
  }
  // The worker thread: runs each begun step in the arena, then says so.
  void work() {
    std::unique_lock lock(mutex_);
    for (;;) {
      changed_.wait(lock, [&] { return quit_ || (running_ && begun_.out); });
      if (quit_) return;
      const Begun begun = std::exchange(begun_, {});
      lock.unlock();
      try {
        in_arena([&] { step(begun.pairs, *begun.out); });
      } catch (...) {
        lock.lock();
        error_ = std::current_exception();
        lock.unlock();
      }
      lock.lock();
      running_ = false;
      changed_.notify_all();
    }
  }

  struct Body {
    ShapeId shape;
    Pose pose;
    bool alive;
    Pose previous;      // the pose at the last step the body was in a pair,
    uint64_t seen = 0;  // that step (0: never): motions are measured between consecutive steps
  };
  // A pair's state is kept by id order, whatever order the host names the
  // pair in: direction 0 is the lower id's rays into the higher, 1 the reverse.
  static int direction(BodyId source, BodyId target) { return source < target ? 0 : 1; }
  // The body of a pair whose edges are tested: both (kAnyBody) unless
  // Config::edges_both_sides is off and both are meshes; then the finer mesh
  // (its longest edge shorter; on a tie the lower id). Either mesh's edges
  // find every crossing region but one where the other passes a part free
  // of vertices right through a wall of it (docs/knobs.md).
  static constexpr BodyId kAnyBody = ~BodyId(0);
  BodyId edge_side(const BodyPair& p) const {
    const ShapeEntry& a = shapes_[bodies_[p.a].shape];
    const ShapeEntry& b = shapes_[bodies_[p.b].shape];
    if (config_.edges_both_sides || !a.shape->mesh() || !b.shape->mesh()) return kAnyBody;
    if (a.longest_edge != b.longest_edge) return a.longest_edge < b.longest_edge ? p.a : p.b;
    return std::min(p.a, p.b);
  }
  struct PairState {
    Pose relative_at_full;               // lower id's frame in the higher id's (a half-space's: the other way)
    std::vector<RayOutcome> tracked[2];  // last kept outcomes, by direction
    Residence residence[2];              // where the executor keeps them, by direction
    // Watched edges at rest while the pair's vertex rays report contacts
    // (Config::edges_beside_contacts off), as their last outcomes.
    std::vector<RayOutcome> resting[2];
    // Where the pair's edges were last tested (Config::edge_retest_motion).
    Pose relative_at_edge_test;
    // The executor's copy of a direction's rays lacks the edges held last step.
    bool held[2] = {false, false};
    // Config::trace_separated_pairs off: a lower bound on the gap between the two
    // surfaces at relative_at_certificate (0: not certified). The pair
    // casts nothing while its motion since, plus its distance extension,
    // stays under it.
    double apart = 0.0;
    Pose relative_at_certificate;
    // A walking pair the bounds proved apart: traced in full next step, where
    // no vertex inside either body shows neither holds the other.
    bool promoted = false;
    // A walking pair the bounds could not prove apart is tried again once it
    // has moved this far from where it was tried.
    Pose relative_at_attempt;
    double retry_after = -1.0;  // < 0: never tried
  };
  // The step's two batches (Algorithm 2): pairs traced in full (new, sent
  // back by equation 2.1, or every pair in full mode), and pairs walked.
  // Certified pairs are in neither.
  enum Batch : uint32_t { kTraced = 0, kWalked = 1, kCertified = 2 };
  // A pair's step: its state and limits, and where its two jobs are, in
  // the host's order: batches_[batch].jobs[first] (a's rays), [first + 1] (b's).
  struct PairWork {
    PairState* state;
    bool fresh;
    PairLimits limits;
    double moved;  // walking pairs: equation 2.1 since the pair's last full step
    bool hold_edges;  // walking pairs: their watched edges are not tested (Config::edge_retest_motion)
    Batch batch;
    uint32_t first;
    Pose relative;  // as PairState::relative_at_full, this step
    bool expired;   // its certificate expired this step
    bool granted;   // certified this step
    double step_motion;  // equation 2.1 since the last step, when limits are derived (else 0)
    bool motion_measured;  // step_motion is that of the last step's poses to this step's: both bodies were in pairs
  };

  Body& body_at(BodyId id) {
    if (id >= bodies_.size() || !bodies_[id].alive) throw UsageError("unknown body " + std::to_string(id));
    return bodies_[id];
  }
  void validate(std::span<const BodyPair> pairs);
  void prepare(std::span<const BodyPair> pairs, StepResult& out);
  void decide(BodyPair pair, PairWork& work) const;
  void place(RayJob& job, BodyId source, BodyId target) const;
  std::span<const RayOutcome> walked(PairState& state, int direction, bool hold) const;
  void restore_held_edges(std::span<const BodyPair> pairs);
  void gather(std::span<const BodyPair> pairs, StepResult& out);
  void certify(BodyPair pair, PairWork& work, const PairResult& result) const;
  double apart(BodyId source, BodyId target, double cap, double floor) const;
  double certificate_slack(BodyPair pair, const Pose& relative) const;
  void fill(const RayJob& job, std::span<const RayOutcome> outcomes, BodyId source, BodyId target, Side side,
            Contact*& contacts, PredictiveRay*& predictive) const;
  void fill_edge(const RayJob& job, const RayOutcome& o, BodyId source, BodyId target, Side side, Contact& c) const;
  void measure_out(const ShapeEntry& target, int32_t face, const Eigen::Vector3d& p,
                   const Eigen::Matrix3d& target_rotation, Contact& c) const;

  std::string name_;
  std::vector<std::string> devices_;
  std::unique_ptr<RayExecutor> executor_;
  std::optional<tbb::task_arena> arena_;  // threads > 0: this narrow phase's own
  bool derive_;  // some limit follows the scene: shapes are measured, motions tracked
  rtcd_limit_settings limit_settings_;  // the configuration's, as derive_limits reads them
  std::vector<ShapeEntry> shapes_;
  std::vector<Body> bodies_;
  std::vector<rtcd_pose> poses_;  // bodies_'s poses as the frames take them (rtcd_relative_frame)
  // Pair states by key, ascending: each step merges them with the step's
  // sorted keys in one sequential pass (a hash map's scattered nodes cost
  // a cache miss per pair), into the other buffer of each pair.
  std::vector<uint64_t> state_keys_, next_keys_;
  std::vector<PairState> states_, next_states_;
  uint64_t step_ = 0;
  // Per-step buffers, kept across steps.
  std::vector<std::pair<uint64_t, uint32_t>> keys_;  // the step's pair keys with their input indices, ascending
  RayBatch batches_[2];                              // by Batch
  std::vector<PairWork> work_;                       // by input index
  // detect_begin's worker and its handoff: the begun step, whether it runs,
  // what it threw. busy_ is the caller's side: a step begun and not ended.
  struct Begun {
    std::span<const BodyPair> pairs;
    StepResult* out = nullptr;
  };
  std::thread worker_;
  mutable std::mutex mutex_;
  std::condition_variable changed_;
  Begun begun_;
  bool running_ = false, quit_ = false, busy_ = false;
  std::exception_ptr error_;
};

void PipelineNarrowPhase::validate(std::span<const BodyPair> pairs) {
  keys_.clear();
  for (const BodyPair& p : pairs) {
    body_at(p.a);
    body_at(p.b);
    if (p.a == p.b) throw UsageError(pair_text(p.a, p.b) + " is one body");
    keys_.push_back({pair_key(p.a, p.b), uint32_t(keys_.size())});
  }
  // Broad phases usually list their pairs sorted already.
  if (!std::is_sorted(keys_.begin(), keys_.end())) std::sort(keys_.begin(), keys_.end());
  const auto twice =
      std::adjacent_find(keys_.begin(), keys_.end(), [](const auto& x, const auto& y) { return x.first == y.first; });
  if (twice != keys_.end())
    throw UsageError(pair_text(pair_of_key(twice->first).a, pair_of_key(twice->first).b) +
                     " appears twice in one step");
}

void PipelineNarrowPhase::step(std::span<const BodyPair> pairs, StepResult& out) {
  // One clock reading per stage boundary: on some machines a reading costs
  // as much as a walk.
  auto lap = [last = Clock::now()]() mutable {
    const auto now = Clock::now();
    const double seconds = seconds_between(last, now);
    last = now;
    return seconds;
  };
  out.stats.reset();
  prepare(pairs, out);
  out.stats.seconds_prepare = lap();
  executor_->begin_step(poses_);
  for (Batch b : {kTraced, kWalked}) batches_[b].counted = {};
  for (Batch b : {kTraced, kWalked}) {
    executor_->execute(batches_[b]);
    (b == kWalked ? out.stats.seconds_iterative : out.stats.seconds_full) = lap();
  }
  executor_->account(out.stats);
  restore_held_edges(pairs);
  gather(pairs, out);
  out.stats.seconds_gather = lap();
}

// Pair state, limits, mode and both jobs per pair.
void PipelineNarrowPhase::prepare(std::span<const BodyPair> pairs, StepResult& out) {
  ++step_;
  work_.resize(pairs.size());
  out.pairs.resize(pairs.size());
  // The step's pairs take their states along, in key order; states of pairs
  // absent from this step are left behind and dropped.
  next_keys_.clear();
  next_states_.clear();
  size_t old = 0;
  for (const auto& [key, i] : keys_) {
    while (old < state_keys_.size() && state_keys_[old] < key) ++old;
    const bool fresh = old == state_keys_.size() || state_keys_[old] != key;
    next_keys_.push_back(key);
    if (fresh) {
      next_states_.emplace_back();
    } else {
      next_states_.push_back(std::move(states_[old++]));
    }
    work_[i].fresh = fresh;
  }
  std::swap(state_keys_, next_keys_);
  std::swap(states_, next_states_);
  for (size_t k = 0; k < keys_.size(); ++k) work_[keys_[k].second].state = &states_[k];

  // Limits and mode touch only the pair's own state: on several threads once
  // there are enough pairs.
  const bool parallel = pairs.size() >= kParallelPairs;
  for_each_index(pairs.size(), parallel, [&](size_t i) { decide(pairs[i], work_[i]); });

  // Each pair's place in its batch, in input order.
  uint32_t jobs[2] = {0, 0};
  for (size_t i = 0; i < pairs.size(); ++i) {
    PairWork& w = work_[i];
    out.stats.certificates_expired += w.expired;
    if (w.batch == kCertified) {
      ++out.stats.pairs_certified;
      continue;
    }
    const bool iterative = w.batch == kWalked;
    out.stats.fallbacks_to_full += !w.fresh && config_.mode == Mode::automatic && !iterative && !w.expired &&
                                   !w.state->promoted;
    ++(iterative ? out.stats.pairs_iterative : out.stats.pairs_full);
    w.first = jobs[w.batch];
    jobs[w.batch] += 2;
  }
  for (Batch b : {kTraced, kWalked}) {
    batches_[b].iterative = b == kWalked;
    batches_[b].resize(jobs[b]);
  }

  // Both jobs of each pair, their transforms and candidate boxes:
  // independent per pair, so on several threads once there are enough.
  for_each_index(pairs.size(), parallel, [&](size_t i) {
    const BodyPair p = pairs[i];
    PairWork& w = work_[i];
    const bool iterative = w.batch == kWalked;
    PairResult& pr = out.pairs[i];
    pr = PairResult{};
    pr.pair = p;
    if (w.batch == kCertified) {
      pr.mode = PairMode::certified;
      return;
    }
    pr.mode = iterative ? PairMode::iterative : PairMode::full;
    const BodyId edges = edge_side(p);
    for (uint32_t k = 0; k < 2; ++k) {
      const BodyId source = k == 0 ? p.a : p.b, target = k == 0 ? p.b : p.a;
      RayJob& job = batches_[w.batch].jobs[w.first + k];
      job.source = bodies_[source].shape;
      job.target = bodies_[target].shape;
      job.iterative = iterative;
      job.edges = edges == kAnyBody || edges == source;
      job.limits = w.limits;
      job.moved = iterative ? w.moved : 0.0;
      job.motion = w.step_motion;
      job.motion_measured = w.motion_measured;
      job.residence = &w.state->residence[direction(source, target)];
      job.tracked =
          iterative ? walked(*w.state, direction(source, target), w.hold_edges) : std::span<const RayOutcome>{};
      place(job, source, target);
    }
  });

  if (derive_) {
    for (const BodyPair& p : pairs)
      for (const BodyId id : {p.a, p.b}) {
        bodies_[id].previous = bodies_[id].pose;
        bodies_[id].seen = step_;
      }
  }
}

// The pair's limits and mode: new pairs are full; Mode::automatic walks while
// equation 2.1 since the last full step stays within the pair's threshold.
void PipelineNarrowPhase::decide(BodyPair p, PairWork& w) const {
  const BodyId lo = std::min(p.a, p.b), hi = std::max(p.a, p.b);
  const Body &low = bodies_[lo], &high = bodies_[hi];
  // Equation 2.1 bounds the motion of the points of the body the relative
  // pose maps, which must lie within `radius` of its origin
  // (rtcd_pair_relative). The kernel's functions: a device derives the
  // pair's motion with them from the poses of this step and the last.
  const double low_radius = shapes_[low.shape].shape->radius(), high_radius = shapes_[high.shape].shape->radius();
  rtcd_pose relative_now;
  rtcd_pair_relative(&poses_[lo], &poses_[hi], low_radius, &relative_now);
  const Pose relative = from_kernel(relative_now);
  const double radius = std::max(low_radius, high_radius);
  w.motion_measured = derive_ && low.seen > 0 && low.seen + 1 == step_ && high.seen > 0 && high.seen + 1 == step_;
  if (derive_) {
    double motion = 0.0;
    if (w.motion_measured) {
      const rtcd_pose low_before = to_kernel(low.previous), high_before = to_kernel(high.previous);
      motion = rtcd_pair_motion(&low_before, &high_before, &poses_[lo], &poses_[hi], low_radius, high_radius);
    }
    w.limits = derive_limits(limit_settings_, shapes_[low.shape].scale, shapes_[high.shape].scale, motion);
    w.step_motion = motion;
  } else {
    w.limits = {*config_.displacement_threshold, *config_.distance_extension, *config_.max_walk_steps};
    w.step_motion = 0.0;
  }
  PairState& state = *w.state;
  w.relative = relative;
  w.expired = w.granted = false;
  bool forced = false;  // to a full trace: an expired certificate, or a promotion
  if (state.apart > 0.0) {
    const double since = max_displacement(state.relative_at_certificate, relative, radius);
    if (since + w.limits.distance_extension + certificate_slack(p, relative) < state.apart) {
      w.batch = kCertified;
      return;
    }
    state.apart = 0.0;
    w.expired = forced = true;
  }
  if (state.promoted) forced = true;
  bool iterative = false;
  w.moved = w.fresh || config_.mode == Mode::full ? 0.0 : max_displacement(state.relative_at_full, relative, radius);
  if (!w.fresh && config_.mode == Mode::iterative) iterative = true;
  if (!w.fresh && config_.mode == Mode::automatic) iterative = w.moved <= w.limits.displacement_threshold;
  if (forced) iterative = false;
  w.hold_edges = iterative && config_.edge_retest_motion &&
                 max_displacement(state.relative_at_edge_test, relative, radius) < *config_.edge_retest_motion;
  if (config_.edge_retest_motion && !w.hold_edges) state.relative_at_edge_test = relative;
  if (!iterative) {
    state.relative_at_full = relative;
    for (int d : {0, 1}) {
      state.tracked[d].clear();
      state.resting[d].clear();
    }
  }
  w.batch = iterative ? kWalked : kTraced;
}

// A walking direction's tracked rays to walk. With edges_beside_contacts off,
// a pair whose vertex rays reported contacts the step before leaves its
// watched edges out (they come last, after the origins): the contacts hold
// the pair, and the edges near them cost most of a resting pair's walk. Once
// no vertex contact is left, the resting edges are walked again; the
// executor's copy of the rays no longer matches, so it is given them anew.
//
// A pair that holds its edges (Config::edge_retest_motion) walks its origins
// and the edges that crossed last step; restore_held_edges gives the other
// edges' last outcomes (watched: no crossing) back to the step.
std::span<const RayOutcome> PipelineNarrowPhase::walked(PairState& state, int d, bool hold) const {
  std::vector<RayOutcome>& tracked = state.tracked[d];
  if (!hold && !state.held[d] && config_.edges_beside_contacts) return tracked;  // the default: every ray walks
  // The rays are reordered, copied or handed over anew below: their walk
  // starts, not the executor's placeholders.
  executor_->recover(state.residence[d], tracked);
  const auto edges = std::find_if(tracked.begin(), tracked.end(), [](const RayOutcome& o) { return o.edge != 0; });
  const bool mesh_edges =
      std::all_of(edges, tracked.end(), [](const RayOutcome& o) { return o.edge == RTCD_ITEM_EDGE; });
  if (hold && mesh_edges) {
    // Edges that crossed are tested again: a contact is never reported from
    // an old test. The watched ones, behind them, are held.
    auto crossed = [](const RayOutcome& o) { return o.kind == RTCD_RAY_PENETRATING; };
    if (!std::is_partitioned(edges, tracked.end(), crossed)) {
      std::partition(edges, tracked.end(), crossed);
      state.residence[d].drop_rays();
    }
    return {tracked.data(), size_t(std::partition_point(edges, tracked.end(), crossed) - tracked.begin())};
  }
  if (state.held[d]) state.residence[d].drop_rays();
  state.held[d] = false;
  if (config_.edges_beside_contacts) return tracked;
  auto vertex_contact = [](const RayOutcome& o) { return o.edge == 0 && o.kind == RTCD_RAY_PENETRATING; };
  const bool witnessed = std::any_of(state.tracked[0].begin(), state.tracked[0].end(), vertex_contact) ||
                         std::any_of(state.tracked[1].begin(), state.tracked[1].end(), vertex_contact);
  if (witnessed && mesh_edges) return {tracked.data(), size_t(edges - tracked.begin())};
  if (!witnessed && !state.resting[d].empty()) {
    tracked.insert(tracked.end(), state.resting[d].begin(), state.resting[d].end());
    state.resting[d].clear();
    state.residence[d].drop_rays();
  }
  return tracked;
}

// Each direction from the two poses, not one from the other's inverse:
// numbering the bodies the other way round then changes no bit. The
// kernel's function, which a device runs on the same poses for the same bits.
void PipelineNarrowPhase::place(RayJob& job, BodyId source, BodyId target) const {
  job.source_body = source;
  job.target_body = target;
  const rtcd_box source_bounds = to_kernel(shapes_[job.source].shape->bounds());
  const rtcd_box target_bounds = to_kernel(shapes_[job.target].shape->bounds());
  rtcd_frame f;
  rtcd_relative_frame(&poses_[source], &poses_[target], &source_bounds, &target_bounds,
                      job.limits.distance_extension, &f);
  for (int i = 0; i < 3; ++i) {
    for (int k = 0; k < 3; ++k) job.rotation(i, k) = f.rotation[3 * i + k];
    job.translation[i] = f.translation[i];
    job.overlap.min[i] = f.lo[i];
    job.overlap.max[i] = f.hi[i];
  }
}

// The watched edges a walking pair held (Config::edge_retest_motion) rejoin
// its directions' outcomes as they were, so they stay tracked. The
// executor's copy of the rays now lacks them, so the state notes it.
void PipelineNarrowPhase::restore_held_edges(std::span<const BodyPair> pairs) {
  for (size_t i = 0; i < pairs.size(); ++i) {
    const PairWork& w = work_[i];
    if (w.batch != kWalked || !w.hold_edges) continue;
    RayBatch& batch = batches_[kWalked];
    for (uint32_t k = 0; k < 2; ++k) {
      const BodyId source = k == 0 ? pairs[i].a : pairs[i].b, target = k == 0 ? pairs[i].b : pairs[i].a;
      const int d = direction(source, target);
      const std::vector<RayOutcome>& last = w.state->tracked[d];
      const size_t walked = batch.jobs[w.first + k].tracked.size();
      if (last.size() == walked) continue;
      std::vector<RayOutcome>& kept = batch.outcomes[w.first + k];
      RayTally& tally = batch.tallies[w.first + k];
      for (auto o = last.begin() + walked; o != last.end(); ++o) {
        kept.push_back(*o);
        tally.hold();
      }
      w.state->held[d] = true;
    }
  }
}

// Ranges per pair in input order (a's rays, then b's), then every record
// filled in parallel, and the kept outcomes handed to the pair's state as
// its tracked rays.
void PipelineNarrowPhase::gather(std::span<const BodyPair> pairs, StepResult& out) {
  size_t outcomes = 0, contacts = 0, predictive = 0;
  RayTally step;
  for (size_t i = 0; i < pairs.size(); ++i) {
    const PairWork& w = work_[i];
    PairResult& pr = out.pairs[i];
    if (w.batch == kCertified) {
      pr.first_contact = contacts;
      pr.first_predictive = predictive;
      continue;
    }
    const RayBatch& batch = batches_[w.batch];
    RayTally pair = batch.tallies[w.first];
    pair += batch.tallies[w.first + 1];
    pr.first_contact = contacts;
    pr.contact_count = pair.contacts;
    pr.first_predictive = predictive;
    pr.predictive_count = pair.predictive;
    pr.colliding = pair.contacts > 0;
    pr.device = batch.tallies[w.first].place;
    contacts += pair.contacts;
    predictive += pair.predictive;
    outcomes += batch.outcomes[w.first].size() + batch.outcomes[w.first + 1].size();
    step += pair;
  }
  for (Batch b : {kTraced, kWalked}) static_cast<RayCounts&>(step) += batches_[b].counted;
  static_cast<RayCounts&>(out.stats) = step;
  out.contacts.resize(contacts);
  out.predictive.resize(predictive);

  for_each_index(pairs.size(), outcomes >= kParallelFill, [&](size_t i) {
    const PairWork& w = work_[i];
    if (w.batch == kCertified) return;
    const BodyPair p = pairs[i];
    PairResult& pr = out.pairs[i];
    Contact* contact = out.contacts.data() + pr.first_contact;
    PredictiveRay* ahead = out.predictive.data() + pr.first_predictive;
    for (uint32_t k = 0; k < 2; ++k) {
      const BodyId source = k == 0 ? p.a : p.b, target = k == 0 ? p.b : p.a;
      RayBatch& batch = batches_[w.batch];
      std::vector<RayOutcome>& kept = batch.outcomes[w.first + k];
      const RayTally& tally = batch.tallies[w.first + k];
      // Most jobs of a settled pile report nothing and only track.
      if (tally.contacts + tally.predictive > 0)
        fill(batch.jobs[w.first + k], kept, source, target, k == 0 ? Side::a : Side::b, contact, ahead);
      // The kept outcomes become the tracked rays; the slot takes the old
      // ones' buffer for a later step. Edges the job left out rest.
      const int d = direction(source, target);
      kept.swap(w.state->tracked[d]);
      const size_t walked = batch.jobs[w.first + k].tracked.size();
      if (batch.iterative && !w.state->held[d] && kept.size() > walked)
        w.state->resting[d].insert(w.state->resting[d].end(), kept.begin() + walked, kept.end());
    }
    for (const Contact& contact : out.contacts_of(pr)) pr.max_depth = std::max(pr.max_depth, contact.depth);
  });

  if (config_.trace_separated_pairs || config_.mode == Mode::full) return;
  for_each_index(pairs.size(), pairs.size() >= kParallelPairs, [&](size_t i) { certify(pairs[i], work_[i], out.pairs[i]); });
  for (const PairWork& w : work_) out.stats.certificates_granted += w.granted;
}

// Slack under a certificate for the kernel's float tests: far above their
// resolution (1e-7 of the larger body, or of the coordinates of a body in
// a half-space's frame).
double PipelineNarrowPhase::certificate_slack(BodyPair p, const Pose& relative) const {
  const double ra = shapes_[bodies_[p.a].shape].shape->radius(), rb = shapes_[bodies_[p.b].shape].shape->radius();
  return 1e-5 * (ra + rb + relative.position.norm());
}

// A pair with nothing to report this step, proven apart by more than its
// distance extension: certified when it was traced in full (no vertex of
// either inside the other, so neither holds the other), promoted to a full
// trace next step when it walked.
void PipelineNarrowPhase::certify(BodyPair p, PairWork& w, const PairResult& pr) const {
  PairState& state = *w.state;
  state.promoted = false;
  if (w.batch == kCertified || pr.contact_count + pr.predictive_count > 0) return;
  const double ra = shapes_[bodies_[p.a].shape].shape->radius(), rb = shapes_[bodies_[p.b].shape].shape->radius();
  if (w.batch == kWalked && state.retry_after >= 0.0 &&
      max_displacement(state.relative_at_attempt, w.relative, std::max(ra, rb)) < state.retry_after)
    return;
  const double need = w.limits.distance_extension + certificate_slack(p, w.relative);
  // How far a proof reaches: as far again as the extension, or a quarter of
  // the smaller body; features farther from the other's box are not looked at.
  const double small = ra == 0.0 ? rb : rb == 0.0 ? ra : std::min(ra, rb);
  const double cap = need + std::max(w.limits.distance_extension, 0.25 * small) + kCertificateSteps * w.step_motion;
  // A certificate the pair's speed would spend within a few steps costs more
  // full traces than it saves.
  const double floor = need + kCertificateSteps * w.step_motion;
  const double gap = std::min(apart(p.a, p.b, cap, floor), apart(p.b, p.a, cap, floor));
  if (gap <= floor) {
    // Apart but moving too fast: tried again next step. Too near: once it
    // has moved as far as the gap lacks.
    if (gap > need) return;
    state.relative_at_attempt = w.relative;
    state.retry_after = std::max(need - gap, 0.1 * need);
    return;
  }
  state.retry_after = -1.0;
  if (w.batch == kWalked) {
    state.promoted = true;
    return;
  }
  state.apart = gap;
  state.relative_at_certificate = w.relative;
  w.granted = true;
  for (int d : {0, 1}) {
    state.tracked[d].clear();
    state.resting[d].clear();
    state.residence[d].drop_rays();
    state.held[d] = false;
  }
}

// A lower bound on the distance from the source's surface to the target's,
// from the source's features (vertices and edges, in pieces no longer than
// the proof's reach) near the target's box, read off the target's distance
// bound; at most `cap`. The closest points of two polyhedral surfaces are a
// vertex and a face or two edges, so the two directions together bound the
// gap. A sphere source: its centre's bound less its radius; a half-space
// source adds nothing (the other body's vertices bound its gap). Stops once
// the bound is at most `floor`.
double PipelineNarrowPhase::apart(BodyId source, BodyId target, double cap, double floor) const {
  const Shape& src = *shapes_[bodies_[source].shape].shape;
  const Shape& dst = *shapes_[bodies_[target].shape].shape;
  const Pose to_target = bodies_[target].pose.inverse() * bodies_[source].pose;
  const Eigen::Matrix3d rotation = to_target.orientation.toRotationMatrix();
  const Eigen::Vector3d& translation = to_target.position;
  const DistanceBound& bound = dst.distance_bound();
  if (std::holds_alternative<HalfSpace>(src.geometry())) return cap;
  if (const auto* sphere = std::get_if<Sphere>(&src.geometry()))
    return std::min(cap, bound.lower(translation) - sphere->radius);
  const RaySources& rs = src.sources();
  const double piece = std::max(cap - floor, 1e-300);
  double gap = cap;
  // A node's items lie within half its box's diagonal of its centre: one
  // lookup there passes over all of them when they cannot lower the gap.
  rs.visit_leaves(
      [&](const Eigen::Vector3f& lo, const Eigen::Vector3f& hi) {
        if (gap <= floor) return false;
        const Eigen::Vector3d centre = 0.5 * (lo + hi).cast<double>();
        return bound.lower(rotation * centre + translation) - 0.5 * (hi - lo).cast<double>().norm() < gap;
      },
      [&](uint32_t leaf) {
        for (uint32_t item : rs.items_of(leaf)) {
          if (gap <= floor) return;
          if (item < rs.first_edge()) {
            gap = std::min(gap, bound.lower(rotation * rs.origins[item].cast<double>() + translation));
            continue;
          }
          const auto& e = rs.edges[item - rs.first_edge()];
          const Eigen::Vector3d a = rotation * rs.origins[e[0]].cast<double>() + translation;
          const Eigen::Vector3d b = rotation * rs.origins[e[1]].cast<double>() + translation;
          const double length = (b - a).norm();
          const int pieces = int(std::clamp(std::ceil(length / piece), 1.0, 64.0));
          for (int k = 0; k < pieces; ++k) {
            const Eigen::Vector3d middle = a + (b - a) * ((k + 0.5) / pieces);
            gap = std::min(gap, bound.lower(middle) - 0.5 * length / pieces);
          }
        }
      });
  return gap;
}

void PipelineNarrowPhase::fill(const RayJob& job, std::span<const RayOutcome> outcomes, BodyId source_id,
                               BodyId target_id, Side side, Contact*& contacts, PredictiveRay*& predictive) const {
  const Body& src = bodies_[source_id];
  const Body& dst = bodies_[target_id];
  const ShapeEntry& source = shapes_[src.shape];
  const ShapeEntry& target = shapes_[dst.shape];
  const Eigen::Matrix3d source_rotation = src.pose.orientation.toRotationMatrix();
  const Eigen::Matrix3d target_rotation = dst.pose.orientation.toRotationMatrix();
  for (const RayOutcome& o : outcomes) {
    if (o.kind == RTCD_RAY_WATCHED) continue;
    if (o.edge) {
      fill_edge(job, o, source_id, target_id, side, *contacts++);
      continue;
    }
    const Eigen::Vector3d origin = source.shape->sources().origins[o.vertex].cast<double>();
    const Eigen::Vector3d& direction = source.directions[o.vertex];
    // In the target's frame: keep the executor's decision, sharpen the distance.
    const Eigen::Vector3d p = job.rotation * origin + job.translation;
    const Eigen::Vector3d d = job.rotation * direction;
    const double refined = target.exit_distance(o.triangle, p, d);
    const double t = o.kind == RTCD_RAY_PENETRATING ? std::max(refined, 0.0) : std::min(refined, 0.0);
    const bool penetrating = o.kind == RTCD_RAY_PENETRATING;
    RayRecord& r = penetrating ? static_cast<RayRecord&>(*contacts) : static_cast<RayRecord&>(*predictive);
    r.source = side;
    r.source_body = source_id;
    r.target_body = target_id;
    r.vertex = o.vertex;
    r.triangle = o.triangle;
    if (penetrating) {
      contacts->kind = ContactKind::vertex;
      contacts->edge = {o.vertex, o.vertex};
    }
    r.origin = source_rotation * origin + src.pose.position;
    // Rotations of unit vectors: unit to double precision.
    r.direction = source_rotation * direction;
    r.normal = target_rotation * target.exit_normal(o.triangle, p + t * d);
    if (penetrating && config_.nearest_surface) {
      // The ray proved the vertex inside; the way out is the nearest surface.
      measure_out(target, o.nearest >= 0 ? o.nearest : target.nearest_face(o.triangle, p), p, target_rotation,
                  *contacts++);
    } else if (penetrating) {
      Contact& c = *contacts++;
      c.depth = t;
      c.projected_depth = t * std::abs(r.direction.dot(r.normal));
      c.push = config_.projected ? Eigen::Vector3d(r.normal * c.projected_depth) : Eigen::Vector3d(r.direction * t);
    } else {
      (predictive++)->distance = -t;
    }
  }
}

}  // namespace

// An edge contact (kernel/trace.h, rtcd_edge_trace: the point at fraction
// t of the edge) or a sphere's deepest point (rtcd_sphere_trace), and the
// way out to the nearest point of the face the executor chose, measured in
// double.
void PipelineNarrowPhase::fill_edge(const RayJob& job, const RayOutcome& o, BodyId source_id, BodyId target_id,
                                    Side side, Contact& c) const {
  const Body& src = bodies_[source_id];
  const Body& dst = bodies_[target_id];
  const ShapeEntry& source = shapes_[src.shape];
  const ShapeEntry& target = shapes_[dst.shape];
  const RaySources& rs = source.shape->sources();
  Eigen::Vector3d p;  // in the target's frame
  if (o.edge == RTCD_ITEM_SPHERE) {
    // From the centre toward the target's centre (sphere) or its nearest point (box).
    const Eigen::Vector3d& centre = job.translation;
    Eigen::Vector3d toward = -centre;
    if (const auto* box = std::get_if<Box>(&target.shape->geometry()))
      toward = centre.cwiseMax(-box->half_extents).cwiseMin(box->half_extents) - centre;
    p = centre + toward.normalized() * std::get<Sphere>(source.shape->geometry()).radius;
    c.kind = ContactKind::sphere;
    c.vertex = 0;
    c.edge = {0, 0};
  } else {
    const auto& e = rs.edges[o.vertex - rs.first_edge()];
    const Eigen::Vector3d p0 = rs.origins[e[0]].cast<double>(), p1 = rs.origins[e[1]].cast<double>();
    p = job.rotation * (p0 + double(o.t) * (p1 - p0)) + job.translation;
    c.kind = ContactKind::edge;
    c.vertex = e[0];
    c.edge = e;
  }
  c.source = side;
  c.source_body = source_id;
  c.target_body = target_id;
  c.origin = dst.pose.orientation * p + dst.pose.position;
  measure_out(target, o.triangle, p, dst.pose.orientation.toRotationMatrix(), c);
}

// A contact's way out to the nearest point of the target's face `face` from
// p (the target's frame), in double: its face, depth, direction, normal and
// push. The push runs along the way out by the depth: the surface's normal
// at that point (the face's normal where the point lies inside the face, so
// projecting changes nothing; on a valley's edge or corner, where faces
// meet, the way out itself). On the surface already (touching): out along
// the face's normal.
void PipelineNarrowPhase::measure_out(const ShapeEntry& target, int32_t face, const Eigen::Vector3d& p,
                                      const Eigen::Matrix3d& target_rotation, Contact& c) const {
  const Eigen::Vector3d out = target.nearest_on_face(face, p) - p;
  const Eigen::Vector3d normal = target.exit_normal(face, p + out);
  c.triangle = face;
  c.depth = out.norm();
  c.direction = target_rotation * (c.depth > 0.0 ? Eigen::Vector3d(out / c.depth) : normal);
  c.normal = target_rotation * normal;
  c.projected_depth = c.depth * std::abs(c.direction.dot(c.normal));
  c.push = c.direction * c.depth;
}

RayTally& RayTally::operator+=(const RayTally& o) {
  RayCounts::operator+=(o);
  contacts += o.contacts;
  predictive += o.predictive;
  return *this;
}

RayTally& RayTally::operator+=(const rtcd_tally& t) {
  contacts += t.contacts;
  predictive += t.predictive;
  candidates += t.candidates;
  rays_full += t.rays_full;
  rays_predictive += t.rays_predictive;
  rays_iterative += t.rays_iterative;
  walk_steps += t.walk_steps;
  nearest_queries += t.nearest_queries;
  rays_retraced += t.rays_retraced;
  rays_watched += t.rays_watched;
  fold_casts += t.fold_casts;
  edges_tested += t.edges_tested;
  edges_skipped += t.edges_skipped;
  edge_rays += t.edge_rays;
  edge_contacts += t.edge_contacts;
  for (int e = 0; e < kLineStatusCount; ++e) walk_endings[e] += t.walk_endings[e];
  return *this;
}

RayTally settle_outcomes(std::vector<RayOutcome>& outcomes, bool iterative) {
  rtcd_tally counted;
  rtcd_tally_clear(&counted);
  size_t kept = 0;
  for (size_t i = 0; i < outcomes.size(); ++i) {
    const RayOutcome& o = outcomes[i];
    rtcd_tally_count(&counted, &o, iterative);
    if (o.kind == RTCD_RAY_DROPPED) continue;
    // Walks keep nearly every ray: no copy onto itself (a store the next
    // load would wait for).
    if (kept != i) outcomes[kept] = o;
    ++kept;
  }
  outcomes.resize(kept);
  RayTally tally;
  tally += counted;
  return tally;
}

std::unique_ptr<NarrowPhase> make_pipeline_narrow_phase(std::string name, std::vector<std::string> devices,
                                                        std::unique_ptr<RayExecutor> executor, const Config& config,
                                                        int threads) {
  if (!executor) throw UsageError("make_pipeline_narrow_phase: null executor");
  if (threads < 0) throw UsageError("make_pipeline_narrow_phase: negative thread count");
  return std::make_unique<PipelineNarrowPhase>(std::move(name), std::move(devices), std::move(executor), config,
                                               threads);
}

}  // namespace rtcd
