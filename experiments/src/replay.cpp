// Lockstep replay: one pass over the recording; at each step every
// configuration due runs on the same poses and pairs, then the exact
// reference judges the rays of ours on the sampled steps.
#include "rtcd/experiments/replay.hpp"

#include <algorithm>
#include <chrono>
#include <memory>
#include <optional>

#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include "rtcd/backend.hpp"
#include "rtcd/clock.hpp"
#include "rtcd/narrow_phase.hpp"
#include "rtcd/oracle/exact.hpp"
#include "rtcd/oracle/third_party.hpp"

namespace rtcd::experiments {
namespace {

uint64_t digest(std::span<const Contact> contacts) {
  uint64_t h = 14695981039346656037ull;
  auto mix = [&h](uint64_t v) {
    for (int byte = 0; byte < 8; ++byte, v >>= 8) h = (h ^ (v & 0xff)) * 1099511628211ull;
  };
  for (const Contact& c : contacts) {
    mix(c.source_body);
    mix(c.target_body);
    mix(uint64_t(c.kind));
    mix(c.edge[0]);
    mix(c.edge[1]);
    mix(uint64_t(int64_t(c.triangle)));
  }
  return h;
}

// The shape of every kind, the ground's last.
struct Shapes {
  std::vector<std::shared_ptr<const Shape>> of_kind;
  std::shared_ptr<const Shape> ground = std::make_shared<Shape>(HalfSpace{});
  size_t index(uint32_t kind) const { return kind == sim::Simulation::kGroundKind ? of_kind.size() : kind; }
  const std::shared_ptr<const Shape>& get(uint32_t kind) const {
    return kind == sim::Simulation::kGroundKind ? ground : of_kind[kind];
  }
  size_t count() const { return of_kind.size() + 1; }
};

// One configuration's engine, fed the bodies as they appear.
class Runner {
 public:
  virtual ~Runner() = default;
  virtual std::string name() const = 0;
  virtual void add_body(uint32_t kind, const Pose& pose) = 0;
  virtual void run(const sim::RecordedFrame& frame, ReplayStep& out) = 0;
  // Ours only: the vertices with a contact, per pair and side, of the last run.
  virtual const StepResult* result() const { return nullptr; }
};

class OursRunner final : public Runner {
 public:
  OursRunner(const ReplayConfig& c, const Shapes& shapes)
      : narrow_(make_narrow_phase(c.backend, c.config)), arena_(c.threads), shapes_(shapes) {
    for (size_t k = 0; k < shapes.count(); ++k)
      ids_.push_back(narrow_->add_shape(k < shapes.of_kind.size() ? shapes.of_kind[k] : shapes.ground));
  }
  std::string name() const override { return narrow_->name(); }
  void add_body(uint32_t kind, const Pose& pose) override { narrow_->add_body(ids_[shapes_.index(kind)], pose); }
  void run(const sim::RecordedFrame& frame, ReplayStep& out) override {
    for (size_t i = 0; i < frame.poses.size(); ++i) narrow_->set_pose(BodyId(i), frame.poses[i]);
    const auto t = Clock::now();
    arena_.execute([&] { narrow_->detect(frame.pairs, result_); });
    out.seconds = seconds_since(t);
    const StepStats& s = result_.stats;
    out.seconds_prepare = s.seconds_prepare;
    out.seconds_full = s.seconds_full;
    out.seconds_iterative = s.seconds_iterative;
    out.seconds_gather = s.seconds_gather;
    out.pairs_full = s.pairs_full;
    out.pairs_iterative = s.pairs_iterative;
    out.fallbacks = s.fallbacks_to_full;
    out.pairs_certified = s.pairs_certified;
    out.certificates_granted = s.certificates_granted;
    out.certificates_expired = s.certificates_expired;
    out.counts = s;
    out.devices = s.devices;
    out.cpu_fallback = s.cpu_fallback;
    out.contacts = result_.contacts.size();
    out.predictive = result_.predictive.size();
    for (const PairResult& p : result_.pairs) out.colliding += p.colliding;
    for (const Contact& c : result_.contacts) out.depth_sum += c.depth;
    out.contact_digest = digest(result_.contacts);
  }
  const StepResult* result() const override { return &result_; }

 private:
  std::unique_ptr<NarrowPhase> narrow_;
  tbb::task_arena arena_;
  const Shapes& shapes_;
  std::vector<ShapeId> ids_;
  StepResult result_;
};

// GIMPACT or FCL: every pair queried on its own, on this thread.
template <class PeerShape>
class PeerRunner final : public Runner {
 public:
  PeerRunner(std::string name, const Shapes& shapes) : name_(std::move(name)), shapes_(shapes) {
    for (size_t k = 0; k < shapes.count(); ++k)
      peer_.emplace_back(k < shapes.of_kind.size() ? *shapes.of_kind[k] : *shapes.ground);
  }
  std::string name() const override { return name_; }
  void add_body(uint32_t kind, const Pose&) override { body_shape_.push_back(shapes_.index(kind)); }
  void run(const sim::RecordedFrame& frame, ReplayStep& out) override {
    const auto t = Clock::now();
    for (const BodyPair& p : frame.pairs) {
      const oracle::ReferenceCollision c = collide(peer_[body_shape_[p.a]], frame.poses[p.a],
                                                   peer_[body_shape_[p.b]], frame.poses[p.b]);
      out.colliding += c.colliding;
      out.contacts += c.contacts.size();
      for (const auto& contact : c.contacts) out.depth_sum += contact.depth;
    }
    out.seconds = seconds_since(t);
  }

 private:
  static oracle::ReferenceCollision collide(const oracle::GimpactShape& a, const Pose& pa, const oracle::GimpactShape& b,
                                            const Pose& pb) {
    return a.collide(pa, b, pb);
  }
  static oracle::ReferenceCollision collide(const oracle::FclShape& a, const Pose& pa, const oracle::FclShape& b,
                                            const Pose& pb) {
    return a.collide(pa, b, pb, true, 1'000'000);  // every contact: the query comparable to ours
  }
  std::string name_;
  const Shapes& shapes_;
  std::vector<PeerShape> peer_;
  std::vector<size_t> body_shape_;
};

std::unique_ptr<Runner> make_runner(const ReplayConfig& c, const Shapes& shapes) {
  switch (c.engine) {
    case Engine::ours: return std::make_unique<OursRunner>(c, shapes);
    case Engine::gimpact: return std::make_unique<PeerRunner<oracle::GimpactShape>>("bullet-gimpact", shapes);
    case Engine::fcl: return std::make_unique<PeerRunner<oracle::FclShape>>("fcl", shapes);
  }
  throw std::logic_error("unknown engine");
}

// The exact reference's verdict on one step: per pair and side, the source
// vertices deeper than epsilon inside the other body, and those inside or
// within epsilon of its surface (a contact anywhere else is false). Open
// targets are not judged: they have no inside.
struct Verdict {
  // By pair index; [0] a's origins in b, [1] b's in a; ascending.
  std::vector<std::array<std::vector<uint32_t>, 2>> deep, not_outside;
  std::vector<std::array<bool, 2>> closed;
};

// What the judge needs of the step beside the verdict.
struct Judge {
  const sim::RecordedFrame& frame;
  const std::vector<size_t>& body_shape;
  const std::vector<oracle::ExactShape>& exact;
  double epsilon_scale;
  const oracle::ExactShape& of(BodyId body) const { return exact[body_shape[body]]; }
  double epsilon(const BodyPair& p) const {
    return epsilon_scale * std::max(of(p.a).shape().radius(), of(p.b).shape().radius());
  }
};

Verdict judge_exact(const Judge& j) {
  const sim::RecordedFrame& frame = j.frame;
  Verdict v;
  v.deep.resize(frame.pairs.size());
  v.not_outside.resize(frame.pairs.size());
  v.closed.resize(frame.pairs.size());
  tbb::parallel_for(size_t(0), frame.pairs.size(), [&](size_t i) {
    const BodyPair& p = frame.pairs[i];
    const double epsilon = j.epsilon(p);
    const auto one_side = [&](const oracle::ExactShape& source, const Pose& source_pose, const oracle::ExactShape& target,
                              const Pose& target_pose, int side) {
      v.closed[i][side] = target.closed();
      if (!target.closed()) return;
      const auto rays = target.rays_from(source.shape(), source_pose, target_pose, epsilon);
      for (size_t k = 0; k < rays.size(); ++k) {
        if (rays[k].deep()) v.deep[i][side].push_back(uint32_t(k));
        if (!rays[k].far_outside()) v.not_outside[i][side].push_back(uint32_t(k));
      }
    };
    one_side(j.of(p.a), frame.poses[p.a], j.of(p.b), frame.poses[p.b], 0);
    one_side(j.of(p.b), frame.poses[p.b], j.of(p.a), frame.poses[p.a], 1);
  });
  return v;
}

// A pair with no vertex deep in the other body: does an edge of either
// cross the other deeper than epsilon, or a sphere's cap reach in?
bool crossing_deep(const Judge& j, const BodyPair& p) {
  const double epsilon = j.epsilon(p);
  const Pose &pa = j.frame.poses[p.a], &pb = j.frame.poses[p.b];
  for (int side = 0; side < 2; ++side) {
    const oracle::ExactShape& source = side == 0 ? j.of(p.a) : j.of(p.b);
    const oracle::ExactShape& target = side == 0 ? j.of(p.b) : j.of(p.a);
    if (!target.closed()) continue;
    const Pose &source_pose = side == 0 ? pa : pb, &target_pose = side == 0 ? pb : pa;
    for (double depth : target.edge_depths(source.shape(), source_pose, target_pose))
      if (depth > epsilon) return true;
    if (target.sphere_depth(source.shape(), source_pose, target_pose) > epsilon) return true;
  }
  return false;
}

void count_judged(const Judge& j, const Verdict& v, const StepResult& r, ReplayStep& out) {
  std::vector<uint32_t> hit;
  std::vector<size_t> separate;  // pairs we call separate with no vertex deep in the other body
  for (size_t i = 0; i < r.pairs.size(); ++i) {
    bool deep_vertex = false;
    for (int side = 0; side < 2; ++side) {
      if (!v.closed[i][side]) continue;
      hit.clear();
      for (const Contact& c : r.contacts_of(r.pairs[i]))
        if (int(c.source) == side && c.kind == ContactKind::vertex) hit.push_back(c.vertex);
      const auto& allowed = v.not_outside[i][side];
      for (uint32_t vertex : hit) out.false_rays += !std::binary_search(allowed.begin(), allowed.end(), vertex);
      const auto& deep = v.deep[i][side];
      if (deep.empty()) continue;
      deep_vertex = true;
      std::sort(hit.begin(), hit.end());
      out.deep += deep.size();
      for (uint32_t vertex : deep) out.missed += !std::binary_search(hit.begin(), hit.end(), vertex);
    }
    if (r.pairs[i].colliding) continue;
    if (deep_vertex) {
      ++out.missed_pairs;
    } else {
      separate.push_back(i);
    }
  }
  // Crossings no vertex sees, searched only where we found nothing.
  std::vector<uint8_t> crossed(separate.size(), 0);
  tbb::parallel_for(size_t(0), separate.size(),
                    [&](size_t k) { crossed[k] = crossing_deep(j, j.frame.pairs[separate[k]]); });
  for (uint8_t c : crossed) out.missed_pairs += c;
  // Every contact against the true penetration at its point.
  for (const Contact& c : r.contacts) {
    const oracle::ExactShape& target = j.of(c.target_body);
    if (!target.closed()) continue;
    const Pose& pose = j.frame.poses[c.target_body];
    const double truth = target.penetration(pose.inverse().apply(c.origin));
    const double smaller = std::min(target.shape().radius(), j.of(c.source_body).shape().radius());
    ++out.truth_checked;
    out.over_reports += oracle::over_reports(c.push.norm(), truth, smaller);
  }
  out.judged = true;
}

}  // namespace

const char* to_string(Engine engine) {
  switch (engine) {
    case Engine::ours: return "rtcd";
    case Engine::gimpact: return "GIMPACT";
    case Engine::fcl: return "FCL";
  }
  return "?";
}

std::vector<ReplayRun> replay(const sim::Recording& recording, const std::vector<ReplayConfig>& configs,
                              const ReplayOptions& options) {
  for (const ReplayConfig& c : configs) {
    if (c.every < 1) throw UsageError(c.label + ": every must be at least 1");
    if (c.every > 1 && !c.stateless())
      throw UsageError(c.label + ": a " + to_string(c.config.mode) +
                       " configuration carries pair state from step to step and must run on every step");
    if (c.threads < 1) throw UsageError(c.label + ": threads must be at least 1");
  }
  Shapes shapes;
  shapes.of_kind = sim::make_shapes(recording.scene());
  std::vector<std::unique_ptr<Runner>> runners;
  std::vector<ReplayRun> runs;
  for (const ReplayConfig& c : configs) {
    runners.push_back(make_runner(c, shapes));
    ReplayRun run;
    run.config = c;
    run.engine_name = runners.back()->name();
    run.steps.resize(recording.steps().size());
    runs.push_back(std::move(run));
  }
  std::vector<oracle::ExactShape> exact;
  if (options.judge_every > 0)
    for (size_t k = 0; k < shapes.count(); ++k)
      exact.emplace_back(k < shapes.of_kind.size() ? shapes.of_kind[k] : shapes.ground);

  const std::vector<uint32_t>& kinds = recording.kinds();
  std::vector<size_t> body_shape;
  sim::Recording::Cursor cursor(recording);
  sim::RecordedFrame frame;
  const uint64_t total = recording.steps().size();
  std::vector<double> spent(configs.size(), 0.0);
  while (cursor.next(frame)) {
    const uint64_t step = cursor.index();
    while (body_shape.size() < frame.poses.size()) {
      const size_t id = body_shape.size();
      body_shape.push_back(shapes.index(kinds[id]));
      for (auto& r : runners) r->add_body(kinds[id], frame.poses[id]);
    }
    const bool judge = options.judge_every > 0 && step % options.judge_every == 0;
    const Judge judging{frame, body_shape, exact, options.epsilon_scale};
    std::optional<Verdict> verdict;
    if (judge) verdict = judge_exact(judging);
    bool observed = false;
    for (size_t i = 0; i < runners.size(); ++i) {
      if (step % configs[i].every != 0 || runs[i].stopped()) continue;
      if (configs[i].budget_seconds > 0 && spent[i] > configs[i].budget_seconds) {
        runs[i].stopped_at = step;
        continue;
      }
      ReplayStep& out = runs[i].steps[step];
      out.ran = true;
      out.pairs = frame.pairs.size();
      runners[i]->run(frame, out);
      spent[i] += out.seconds;
      if (verdict && runners[i]->result()) count_judged(judging, *verdict, *runners[i]->result(), out);
      if (options.observe && runners[i]->result() && !observed) {
        options.observe(step, *runners[i]->result());
        observed = true;
      }
    }
    if (options.progress) options.progress(step + 1, total);
  }
  return runs;
}

}  // namespace rtcd::experiments
