// Differential validation (see differential.hpp).
#include "rtcd/validation/differential.hpp"

#include <algorithm>
#include <array>
#include <chrono>
#include <iomanip>
#include <numbers>
#include <optional>
#include <span>
#include <sstream>

#include <nlohmann/json.hpp>

#include "rtcd/backend.hpp"
#include "rtcd/clock.hpp"
#include "rtcd/error.hpp"
#include "rtcd/knobs_json.hpp"
#include "rtcd/narrow_phase.hpp"
#include "rtcd/oracle/exact.hpp"
#include "rtcd/oracle/third_party.hpp"

namespace rtcd::validation {
namespace {

// What our backend said of one ray origin.
struct OurRay {
  double depth = -1.0;   // of its penetrating ray; -1 when it has none
  bool tracked = false;  // iterative runs: a ray was tracked for it after the full step
};

// Judges one direction's rays against the exact reference.
// A ray's depth is judged against what the contact claims to be: the
// distance to the nearest surface (Config::nearest_surface) or the first
// exit along the ray.
void judge(const std::vector<oracle::ExactRay>& exact, const std::vector<OurRay>& ours, bool target_closed,
           bool nearest_surface, double epsilon, PairMetrics& m) {
  size_t inside = 0;
  for (size_t v = 0; v < exact.size(); ++v) {
    const oracle::ExactRay& e = exact[v];
    const bool penetrating = ours[v].depth >= 0.0;
    const double expected = nearest_surface ? e.penetration : e.depth;
    if (penetrating && e.inside && expected >= 0.0) {
      const double error = std::abs(ours[v].depth - expected);
      m.max_depth_error = std::max(m.max_depth_error, error);
      m.max_relative_depth_error = std::max(m.max_relative_depth_error, error / std::max(expected, epsilon));
      m.depth_error_sum += error;
      ++m.depth_checked;
    }
    if (!target_closed) continue;  // no inside/outside claims on an open target
    inside += e.inside;
    if (e.inside) m.deepest_exact = std::max(m.deepest_exact, e.penetration);
    if (e.deep()) {
      ++m.deep;
      m.missed += !penetrating;
      m.missed_untracked += !penetrating && !ours[v].tracked;
    } else if (e.far_outside()) {
      ++m.far_outside;
      m.false_rays += penetrating;
    }
  }
  m.inside_any += inside;
  if (target_closed && inside == exact.size()) m.contained = true;
}

// Every contact of a pair against the true penetration at its point: the
// exact distance to the target's nearest surface (0 outside) and the way
// there. A vertex contact's truth is its ray's (rays_from already measured
// it); edge and sphere contacts are measured here. Ratios and angles only
// where the truth is deeper than epsilon.
void judge_truth(const StepResult& step, const PairResult& pr, const oracle::ExactShape& exact_a,
                 const oracle::ExactShape& exact_b, const std::vector<oracle::ExactRay>& rays_ab,
                 const std::vector<oracle::ExactRay>& rays_ba, const PosePair& poses, double epsilon,
                 double smaller_radius, PairMetrics& m) {
  for (const Contact& c : step.contacts_of(pr)) {
    const bool into_b = c.source == Side::a;
    const oracle::ExactShape& target = into_b ? exact_b : exact_a;
    if (!target.closed()) continue;
    const Pose& pose = into_b ? poses.b : poses.a;
    const Eigen::Vector3d p = pose.inverse().apply(c.origin);
    double truth = 0.0;
    if (c.kind == ContactKind::vertex) {
      const oracle::ExactRay& e = (into_b ? rays_ab : rays_ba)[c.vertex];
      truth = e.inside ? e.penetration : 0.0;
    } else {
      truth = target.penetration(p);
    }
    const double solver = c.push.norm();  // what a host's solver is asked to undo
    ++m.truth_checked;
    m.over_reports += oracle::over_reports(solver, truth, smaller_radius);
    if (!(truth > epsilon) || !(solver > 0.0)) continue;
    const double ratio = solver / truth;
    m.max_truth_ratio = std::max(m.max_truth_ratio, ratio);
    m.truth_ratios.push_back(ratio);
    m.push_angles.push_back(push_angle(c, target, pose, truth, epsilon));
  }
}

double percentile(std::vector<double> v, double q) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  return v[std::min(v.size() - 1, size_t(q * double(v.size())))];
}

std::string pose_text(const Pose& p) {
  std::ostringstream s;
  s << std::setprecision(17) << p.position.x() << ' ' << p.position.y() << ' ' << p.position.z() << ' '
    << p.orientation.w() << ' ' << p.orientation.x() << ' ' << p.orientation.y() << ' ' << p.orientation.z();
  return s.str();
}

// The knobs a run's backend gets: the options' own, in the run's mode.
Config run_config(const RunOptions& options) {
  if (options.pairs == 0) throw UsageError("a validation run needs at least one pair");
  if (options.mode == RunMode::iterative && options.motion_steps == 0)
    throw UsageError("an iterative validation run needs at least one motion step");
  Config config = options.config;
  config.mode = options.mode == RunMode::full ? Mode::full : Mode::automatic;
  config.validate();
  return config;
}

// What a pair is judged against: the exact reference, and FCL, GIMPACT
// (libccd takes the shapes as they are) when the run has the oracles.
struct References {
  References(const Family& family, bool with_oracles) : exact_a(family.a), exact_b(family.b) {
    if (!with_oracles) return;
    fcl_a.emplace(*family.a);
    fcl_b.emplace(*family.b);
    gimpact_a.emplace(*family.a);
    gimpact_b.emplace(*family.b);
  }
  const oracle::ExactShape exact_a, exact_b;
  std::optional<oracle::FclShape> fcl_a, fcl_b;
  std::optional<oracle::GimpactShape> gimpact_a, gimpact_b;
};

double epsilon_of(const Family& family, const RunOptions& options) {
  return options.epsilon_scale * std::max(family.a->radius(), family.b->radius());
}

// One shard: our backend steps its pairs, then each pair is judged, one
// method per job.
class ShardRun {
 public:
  ShardRun(const Family& family, const RunOptions& options, size_t first, size_t count)
      : family(family),
        options(options),
        config(run_config(options)),
        epsilon(epsilon_of(family, options)),
        smaller_radius(std::min(family.a->radius(), family.b->radius())),
        first(first),
        count(count) {}

  Shard run() {
    shard.first = first;
    step_ours();
    const References references(family, options.with_oracles);
    ours_a.resize(family.a->sources().origins.size());
    ours_b.resize(family.b->sources().origins.size());
    shard.pairs.reserve(count);
    for (size_t k = 0; k < count; ++k) shard.pairs.push_back(judge_pair(k, references));
    return std::move(shard);
  }

 private:
  // Our backend: every pair of the shard in one batch, as a host would step them.
  void step_ours();
  // Iterative runs: the steps before the judged one; the seconds of those timed.
  double step_through_motions(NarrowPhase& narrow, std::span<const BodyPair> pairs);
  PairMetrics judge_pair(size_t k, const References& references);
  void mark_our_rays(size_t k, PairMetrics& m);
  void count_crossings(const References& references, PairMetrics& m);
  void run_oracles(const References& references, PairMetrics& m);

  const Family& family;
  const RunOptions& options;
  const Config config;
  const double epsilon, smaller_radius;
  const size_t first, count;
  Shard shard;
  std::vector<PosePair> judged;  // by pair of the shard
  StepResult step;               // the judged one
  // What was tracked going into the judged step (iterative runs).
  std::vector<std::vector<std::pair<Side, uint32_t>>> tracked;
  std::vector<size_t> full_steps;
  std::vector<OurRay> ours_a, ours_b;  // of the pair being judged
};

void ShardRun::step_ours() {
  BackendOptions backend = BackendOptions::parse(options.backend);
  if (options.single_thread) backend.threads = 1;
  auto narrow = make_narrow_phase(backend, config);
  shard.backend = narrow->name();
  const ShapeId sa = narrow->add_shape(family.a), sb = narrow->add_shape(family.b);
  judged.resize(count);
  std::vector<BodyPair> pairs(count);
  for (size_t k = 0; k < count; ++k) {
    judged[k] = random_poses(family, options.seed, first + k);
    pairs[k] = {narrow->add_body(sa, judged[k].a), narrow->add_body(sb, judged[k].b)};
  }
  tracked.resize(count);
  full_steps.assign(count, 0);
  // Of the timed steps: the one full step, or every step after it.
  double seconds = options.mode == RunMode::iterative ? step_through_motions(*narrow, pairs) : 0.0;
  const auto t0 = Clock::now();
  narrow->detect(pairs, step);
  shard.seconds_ours = seconds + seconds_since(t0);
  shard.vertex_rays = step.stats.rays_full + step.stats.rays_predictive + step.stats.rays_iterative;
  shard.edge_rays = step.stats.edge_rays;
  shard.edges_tested = step.stats.edges_tested;
}

double ShardRun::step_through_motions(NarrowPhase& narrow, std::span<const BodyPair> pairs) {
  double seconds = 0.0;
  narrow.detect(pairs, step);
  for (size_t s = 0; s < options.motion_steps; ++s) {
    if (s > 0) {
      const auto t = Clock::now();
      narrow.detect(pairs, step);
      seconds += seconds_since(t);
      for (size_t k = 0; k < count; ++k) full_steps[k] += step.pairs[k].mode == PairMode::full;
    }
    if (s + 1 == options.motion_steps) {
      for (size_t k = 0; k < count; ++k) {
        for (const Contact& c : step.contacts_of(step.pairs[k]))
          if (c.kind == ContactKind::vertex) tracked[k].push_back({c.source, c.vertex});
        for (const PredictiveRay& p : step.predictive_of(step.pairs[k])) tracked[k].push_back({p.source, p.vertex});
      }
    }
    for (size_t k = 0; k < count; ++k) {
      judged[k] = moved(family, judged[k], family.step_motion(), options.seed, first + k);
      narrow.set_pose(pairs[k].a, judged[k].a);
      narrow.set_pose(pairs[k].b, judged[k].b);
    }
  }
  return seconds;
}

PairMetrics ShardRun::judge_pair(size_t k, const References& references) {
  const oracle::ExactShape& exact_a = references.exact_a;
  const oracle::ExactShape& exact_b = references.exact_b;
  PairMetrics m;
  m.index = first + k;
  m.poses = judged[k];
  const PairResult& pr = step.pairs[k];
  m.iterative = pr.mode == PairMode::iterative;
  m.certified = pr.mode == PairMode::certified;
  m.full_steps = full_steps[k] + (options.mode == RunMode::iterative && pr.mode == PairMode::full);
  m.colliding_ours = pr.colliding;
  mark_our_rays(k, m);

  const auto t = Clock::now();
  const auto rays_ab = exact_b.rays_from(*family.a, m.poses.a, m.poses.b, epsilon);
  const auto rays_ba = exact_a.rays_from(*family.b, m.poses.b, m.poses.a, epsilon);
  m.seconds_exact += seconds_since(t);
  judge(rays_ab, ours_a, exact_b.closed(), config.nearest_surface, epsilon, m);
  judge(rays_ba, ours_b, exact_a.closed(), config.nearest_surface, epsilon, m);
  judge_truth(step, pr, exact_a, exact_b, rays_ab, rays_ba, m.poses, epsilon, smaller_radius, m);
  count_crossings(references, m);
  m.colliding_exact = m.deep > 0 || m.crossing_deep > 0;
  m.under_reported = m.deepest_exact > epsilon && m.deepest_ours < 0.8 * m.deepest_exact - 1e-3 * smaller_radius;
  if (options.with_oracles) run_oracles(references, m);
  return m;
}

// Our rays of pair k, per origin: its depth, and whether it was tracked.
void ShardRun::mark_our_rays(size_t k, PairMetrics& m) {
  std::fill(ours_a.begin(), ours_a.end(), OurRay{});
  std::fill(ours_b.begin(), ours_b.end(), OurRay{});
  for (const auto& [side, vertex] : tracked[k]) (side == Side::a ? ours_a : ours_b)[vertex].tracked = true;
  for (const Contact& c : step.contacts_of(step.pairs[k])) {
    // Edge contacts are judged by pair (crossing_deep), vertex rays one by one.
    if (c.kind == ContactKind::vertex) (c.source == Side::a ? ours_a : ours_b)[c.vertex].depth = c.depth;
    m.our_projected_depth = std::max(m.our_projected_depth, c.projected_depth);
    m.deepest_ours = std::max(m.deepest_ours, c.depth);
  }
}

// Edge crossings, and a sphere's cap in a sphere or a box, in closed form.
void ShardRun::count_crossings(const References& references, PairMetrics& m) {
  const auto t = Clock::now();
  for (auto depths : {references.exact_b.edge_depths(*family.a, m.poses.a, m.poses.b),
                      references.exact_a.edge_depths(*family.b, m.poses.b, m.poses.a)})
    for (double depth : depths) {
      m.crossing_deep += depth > epsilon;
      m.crossing_any += depth > 0.0;
      m.deepest_exact = std::max(m.deepest_exact, depth);
    }
  for (double depth : {references.exact_b.sphere_depth(*family.a, m.poses.a, m.poses.b),
                       references.exact_a.sphere_depth(*family.b, m.poses.b, m.poses.a)}) {
    m.crossing_deep += depth > epsilon;
    m.crossing_any += depth > 0.0;
  }
  m.seconds_exact += seconds_since(t);
}

void ShardRun::run_oracles(const References& references, PairMetrics& m) {
  auto t = Clock::now();
  m.fcl = references.fcl_a->collide(m.poses.a, *references.fcl_b, m.poses.b).colliding;
  m.seconds_fcl = seconds_since(t);
  // All contacts, the query comparable to ours.
  t = Clock::now();
  references.fcl_a->collide(m.poses.a, *references.fcl_b, m.poses.b, true, 1'000'000);
  m.seconds_fcl_contacts = seconds_since(t);
  if (m.index < options.gimpact_pairs) {
    t = Clock::now();
    m.gimpact = references.gimpact_a->collide(m.poses.a, *references.gimpact_b, m.poses.b).colliding;
    m.seconds_gimpact = seconds_since(t);
    m.has_gimpact = true;
  }
  if (family.convex) {
    t = Clock::now();
    const auto p = oracle::ccd_penetration(*family.a, m.poses.a, *family.b, m.poses.b);
    m.seconds_ccd = seconds_since(t);
    m.has_ccd = true;
    m.ccd = p.colliding;
    m.ccd_depth = p.depth;
  }
}

// A run's pairs, folded into its summary one by one in pair order.
class SummaryFold {
 public:
  SummaryFold(const Family& family, const RunOptions& options) : options(options) {
    s.family = family.name;
    s.mode = options.mode;
    s.config = run_config(options);
    s.pairs = options.pairs;
    s.seed = options.seed;
    s.epsilon = epsilon_of(family, options);
    s.with_oracles = options.with_oracles;
    if (options.mode == RunMode::iterative) s.motion_steps = options.pairs * options.motion_steps;
  }
  void add(const Shard& shard);
  void add(const PairMetrics& m);
  Summary finish();

 private:
  const RunOptions& options;
  Summary s;
  double seconds_ours = 0.0, depth_error_sum = 0.0, ccd_difference_sum = 0.0, ccd_ratio_sum = 0.0;
  std::vector<double> missed_rates, truth_ratios, push_angles;
};

void SummaryFold::add(const Shard& shard) {
  if (s.backend.empty()) s.backend = shard.backend;
  if (shard.backend != s.backend)
    throw UsageError("a shard of pairs from " + std::to_string(shard.first) + " ran on backend '" + shard.backend +
                     "', the others on '" + s.backend + "'");
  s.vertex_rays += shard.vertex_rays;
  s.edge_rays += shard.edge_rays;
  s.edges_tested += shard.edges_tested;
  seconds_ours += shard.seconds_ours;
  for (const PairMetrics& m : shard.pairs) add(m);
}

void SummaryFold::add(const PairMetrics& m) {
  s.iterative_pairs += m.iterative;
  s.certified_pairs += m.certified;
  s.under_reported_pairs += m.under_reported;
  s.full_steps += m.full_steps;
  s.deep += m.deep;
  s.missed += m.missed;
  s.missed_untracked += m.missed_untracked;
  s.far_outside += m.far_outside;
  s.false_rays += m.false_rays;
  s.depth_checked += m.depth_checked;
  depth_error_sum += m.depth_error_sum;
  s.truth_checked += m.truth_checked;
  s.over_reports += m.over_reports;
  truth_ratios.insert(truth_ratios.end(), m.truth_ratios.begin(), m.truth_ratios.end());
  push_angles.insert(push_angles.end(), m.push_angles.begin(), m.push_angles.end());
  s.max_depth_error = std::max(s.max_depth_error, m.max_depth_error);
  s.max_relative_depth_error = std::max(s.max_relative_depth_error, m.max_relative_depth_error);
  if (m.deep) missed_rates.push_back(m.missed_rate());
  s.colliding += m.colliding_exact;
  s.crossing_pairs += m.colliding_exact && m.deep == 0;
  s.missed_pairs += m.missed_pair();
  s.false_pairs += m.false_pair();
  s.contained += m.contained && m.colliding_exact;
  s.time_exact += m.seconds_exact;
  if (!options.with_oracles) return;
  s.time_fcl += m.seconds_fcl;
  s.time_fcl_contacts += m.seconds_fcl_contacts;
  s.time_gimpact += m.seconds_gimpact;
  s.time_ccd += m.seconds_ccd;
  s.gimpact_runs += m.has_gimpact;
  if (m.colliding_exact && !m.contained) {
    ++s.fcl_checked;
    s.fcl_agree += m.fcl;
    s.gimpact_checked += m.has_gimpact;
    s.gimpact_agree += m.has_gimpact && m.gimpact;
  }
  s.fcl_blind_contained += m.contained && m.colliding_exact && !m.fcl;
  s.fcl_missed_pairs += m.fcl && m.missed_pair();
  s.fcl_touching_pairs += m.fcl && !m.colliding_exact && !m.colliding_ours;
  if (m.has_ccd && m.ccd && m.colliding_ours) {
    ++s.ccd_pairs;
    ccd_difference_sum += std::abs(m.our_projected_depth - m.ccd_depth);
    ccd_ratio_sum += m.our_projected_depth / m.ccd_depth;
  }
}

// Times per pair, means and percentiles, once every pair is in.
Summary SummaryFold::finish() {
  const double n = double(options.pairs);
  // Iterative runs: the mean over the motion steps, full steps they cause included.
  s.time_ours = seconds_ours / (n * double(options.mode == RunMode::iterative ? options.motion_steps : 1));
  s.time_exact /= n;
  s.time_fcl /= n;
  s.time_fcl_contacts /= n;
  s.time_gimpact /= double(std::max<size_t>(s.gimpact_runs, 1));
  s.time_ccd /= n;
  s.mean_depth_error = s.depth_checked ? depth_error_sum / double(s.depth_checked) : 0.0;
  s.missed_p50 = percentile(missed_rates, 0.5);
  s.missed_p90 = percentile(missed_rates, 0.9);
  s.missed_p99 = percentile(missed_rates, 0.99);
  s.missed_max = percentile(missed_rates, 1.0);
  s.truth_ratio_p50 = percentile(truth_ratios, 0.5);
  s.truth_ratio_p99 = percentile(truth_ratios, 0.99);
  s.truth_ratio_max = percentile(truth_ratios, 1.0);
  s.push_angle_p50 = percentile(push_angles, 0.5);
  s.push_angle_p95 = percentile(push_angles, 0.95);
  if (s.ccd_pairs) {
    s.ccd_mean_abs_difference = ccd_difference_sum / double(s.ccd_pairs);
    s.ccd_mean_ratio = ccd_ratio_sum / double(s.ccd_pairs);
  }
  return s;
}

// Every field a shard's JSON holds for a pair, named once for both ways.
template <class Metrics, class Visit>
void visit_fields(Metrics& m, Visit&& visit) {
  visit("index", m.index);
  visit("iterative", m.iterative);
  visit("certified", m.certified);
  visit("deepest_exact", m.deepest_exact);
  visit("deepest_ours", m.deepest_ours);
  visit("under_reported", m.under_reported);
  visit("full_steps", m.full_steps);
  visit("deep", m.deep);
  visit("missed", m.missed);
  visit("missed_untracked", m.missed_untracked);
  visit("far_outside", m.far_outside);
  visit("false_rays", m.false_rays);
  visit("depth_checked", m.depth_checked);
  visit("max_depth_error", m.max_depth_error);
  visit("max_relative_depth_error", m.max_relative_depth_error);
  visit("inside_any", m.inside_any);
  visit("crossing_deep", m.crossing_deep);
  visit("crossing_any", m.crossing_any);
  visit("colliding_exact", m.colliding_exact);
  visit("colliding_ours", m.colliding_ours);
  visit("contained", m.contained);
  visit("fcl", m.fcl);
  visit("has_gimpact", m.has_gimpact);
  visit("gimpact", m.gimpact);
  visit("has_ccd", m.has_ccd);
  visit("ccd", m.ccd);
  visit("ccd_depth", m.ccd_depth);
  visit("our_projected_depth", m.our_projected_depth);
  visit("truth_checked", m.truth_checked);
  visit("over_reports", m.over_reports);
  visit("max_truth_ratio", m.max_truth_ratio);
  visit("depth_error_sum", m.depth_error_sum);
  visit("truth_ratios", m.truth_ratios);
  visit("push_angles", m.push_angles);
  visit("seconds_exact", m.seconds_exact);
  visit("seconds_fcl", m.seconds_fcl);
  visit("seconds_fcl_contacts", m.seconds_fcl_contacts);
  visit("seconds_gimpact", m.seconds_gimpact);
  visit("seconds_ccd", m.seconds_ccd);
}

template <class T>
T field(const nlohmann::json& j, const char* key, const std::string& where) {
  const auto it = j.find(key);
  if (it == j.end()) throw UsageError(where + " has no '" + key + "'");
  try {
    return it->get<T>();
  } catch (const nlohmann::json::exception&) {
    throw UsageError(where + ": '" + key + "' is not what it should be (" + it->dump() + ")");
  }
}

nlohmann::json pose_json(const Pose& p) {
  return {p.position.x(), p.position.y(), p.position.z(), p.orientation.w(),
          p.orientation.x(), p.orientation.y(), p.orientation.z()};
}

Pose pose_from_json(const nlohmann::json& j, const std::string& where) {
  if (!j.is_array() || j.size() != 7) throw UsageError(where + ": a pose is 7 numbers");
  std::array<double, 7> v;
  for (size_t i = 0; i < 7; ++i) {
    if (!j[i].is_number()) throw UsageError(where + ": a pose is 7 numbers");
    v[i] = j[i].get<double>();
  }
  return {{v[0], v[1], v[2]}, Eigen::Quaterniond(v[3], v[4], v[5], v[6])};
}

}  // namespace

double push_angle(const Contact& c, const oracle::ExactShape& target, const Pose& target_pose, double truth,
                  double epsilon) {
  const Eigen::Vector3d p = target_pose.inverse().apply(c.origin);
  const auto angle = [&](const Eigen::Vector3d& way) {
    return std::acos(std::clamp(c.push.normalized().dot(way.normalized()), -1.0, 1.0)) * 180.0 / std::numbers::pi;
  };
  double degrees = angle(target_pose.orientation * (target.closest_point(p) - p));
  if (degrees > 1.0 && c.depth <= truth + epsilon &&
      target.distance(target_pose.inverse().apply(c.origin + c.direction * c.depth)) <= epsilon)
    degrees = angle(c.direction);
  return degrees;
}

const char* to_string(RunMode mode) { return mode == RunMode::full ? "full" : "iterative"; }

RunMode parse_run_mode(const std::string& text) {
  if (text == "full") return RunMode::full;
  if (text == "iterative") return RunMode::iterative;
  throw UsageError("unknown validation mode '" + text + "' (expected full or iterative)");
}

Shard run_shard(const Family& family, const RunOptions& options, size_t first, size_t count) {
  if (count == 0 || first + count > options.pairs)
    throw UsageError("a shard of pairs " + std::to_string(first) + " to " + std::to_string(first + count) +
                     " does not lie in a run of " + std::to_string(options.pairs) + " pairs");
  return ShardRun(family, options, first, count).run();
}

RunResult summarize(const Family& family, const RunOptions& options, std::span<const Shard> shards) {
  SummaryFold fold(family, options);
  RunResult result;
  result.pairs.reserve(options.pairs);
  for (const Shard& shard : shards) {
    for (size_t k = 0; k < shard.pairs.size(); ++k)
      if (shard.first != result.pairs.size() || shard.pairs[k].index != shard.first + k)
        throw UsageError("the shards of a run of " + std::to_string(options.pairs) + " pairs skip or repeat pair " +
                         std::to_string(result.pairs.size() + k));
    fold.add(shard);
    result.pairs.insert(result.pairs.end(), shard.pairs.begin(), shard.pairs.end());
  }
  if (result.pairs.size() != options.pairs)
    throw UsageError("the shards of a run of " + std::to_string(options.pairs) + " pairs hold " +
                     std::to_string(result.pairs.size()));
  result.summary = fold.finish();
  return result;
}

RunResult run_family(const Family& family, const RunOptions& options) {
  const Shard all = run_shard(family, options, 0, options.pairs);
  return summarize(family, options, {&all, 1});
}

std::optional<RunResult> run_family(const Family& family, const RunOptions& options, const ShardRunner& runner) {
  const auto shards = runner.run(family, options);
  if (!shards) return std::nullopt;
  return summarize(family, options, *shards);
}

nlohmann::json to_json(const Summary& s) {
  return {{"family", s.family},
          {"backend", s.backend},
          {"mode", to_string(s.mode)},
          {"knobs", knobs_json(s.config)},
          {"pairs", s.pairs},
          {"seed", s.seed},
          {"epsilon", s.epsilon},
          {"iterative_pairs", s.iterative_pairs},
          {"certified_pairs", s.certified_pairs},
          {"motion_steps", s.motion_steps},
          {"full_step_rate", s.motion_steps ? double(s.full_steps) / double(s.motion_steps) : 0.0},
          {"colliding_fraction", s.colliding_fraction()},
          {"deep_origins", s.deep},
          {"missed", s.missed},
          {"missed_rate", s.missed_rate()},
          {"missed_untracked", s.missed_untracked},
          {"missed_rate_per_pair", {{"p50", s.missed_p50}, {"p90", s.missed_p90}, {"p99", s.missed_p99}, {"max", s.missed_max}}},
          {"far_outside_origins", s.far_outside},
          {"false_rays", s.false_rays},
          {"depth_checked", s.depth_checked},
          {"depth_error", {{"max", s.max_depth_error}, {"mean", s.mean_depth_error}, {"max_relative", s.max_relative_depth_error}}},
          {"truth", {{"contacts", s.truth_checked},
                     {"over_reports", s.over_reports},
                     {"under_reported_pairs", s.under_reported_pairs},
                     {"depth_ratio", {{"p50", s.truth_ratio_p50}, {"p99", s.truth_ratio_p99}, {"max", s.truth_ratio_max}}},
                     {"push_angle_degrees", {{"p50", s.push_angle_p50}, {"p95", s.push_angle_p95}}}}},
          {"oracles", s.with_oracles},
          {"fcl", {{"checked", s.fcl_checked}, {"agreement", s.fcl_agreement()}, {"contained", s.contained},
                   {"blind_contained", s.fcl_blind_contained}, {"missed_pairs", s.fcl_missed_pairs},
                   {"touching_pairs", s.fcl_touching_pairs}}},
          {"missed_pairs", s.missed_pairs},
          {"missed_pair_rate", s.missed_pair_rate()},
          {"false_pairs", s.false_pairs},
          {"crossing_pairs", s.crossing_pairs},
          {"rays_per_pair", {{"vertex", double(s.vertex_rays) / double(s.pairs)},
                             {"edge", double(s.edge_rays) / double(s.pairs)},
                             {"edges_tested", double(s.edges_tested) / double(s.pairs)}}},
          {"gimpact", {{"pairs_run", s.gimpact_runs}, {"checked", s.gimpact_checked}, {"agreement", s.gimpact_agreement()}}},
          {"ccd", {{"pairs", s.ccd_pairs}, {"mean_abs_difference", s.ccd_mean_abs_difference}, {"mean_ratio", s.ccd_mean_ratio}}},
          {"seconds_per_pair", {{"ours", s.time_ours}, {"exact", s.time_exact}, {"fcl", s.time_fcl}, {"fcl_contacts", s.time_fcl_contacts},
                                {"gimpact", s.time_gimpact}, {"ccd", s.time_ccd}}}};
}

nlohmann::json to_json(const Shard& shard) {
  nlohmann::json pairs = nlohmann::json::array();
  for (const PairMetrics& m : shard.pairs) {
    nlohmann::json j;
    visit_fields(m, [&](const char* key, const auto& value) { j[key] = value; });
    j["poses"] = {pose_json(m.poses.a), pose_json(m.poses.b)};
    pairs.push_back(std::move(j));
  }
  return {{"first", shard.first},
          {"backend", shard.backend},
          {"vertex_rays", shard.vertex_rays},
          {"edge_rays", shard.edge_rays},
          {"edges_tested", shard.edges_tested},
          {"seconds_ours", shard.seconds_ours},
          {"pairs", std::move(pairs)}};
}

Shard shard_from_json(const nlohmann::json& j) {
  if (!j.is_object()) throw UsageError("a shard is a JSON object");
  Shard shard;
  shard.first = field<size_t>(j, "first", "the shard");
  const std::string where = "the shard from pair " + std::to_string(shard.first);
  shard.backend = field<std::string>(j, "backend", where);
  shard.vertex_rays = field<size_t>(j, "vertex_rays", where);
  shard.edge_rays = field<size_t>(j, "edge_rays", where);
  shard.edges_tested = field<size_t>(j, "edges_tested", where);
  shard.seconds_ours = field<double>(j, "seconds_ours", where);
  const auto pairs = field<nlohmann::json>(j, "pairs", where);
  if (!pairs.is_array()) throw UsageError(where + ": 'pairs' is not an array");
  for (const nlohmann::json& p : pairs) {
    const std::string pair_where = where + ", pair " + std::to_string(shard.pairs.size());
    if (!p.is_object()) throw UsageError(pair_where + " is not an object");
    PairMetrics m;
    visit_fields(m, [&](const char* key, auto& value) {
      value = field<std::remove_reference_t<decltype(value)>>(p, key, pair_where);
    });
    const auto poses = field<nlohmann::json>(p, "poses", pair_where);
    if (!poses.is_array() || poses.size() != 2) throw UsageError(pair_where + ": 'poses' is not two poses");
    m.poses = {pose_from_json(poses[0], pair_where), pose_from_json(poses[1], pair_where)};
    shard.pairs.push_back(std::move(m));
  }
  return shard;
}

std::string describe(const Family& family, const PairMetrics& m, const RunOptions& o) {
  std::ostringstream s;
  s << "family " << family.name << ", seed " << o.seed << ", pair " << m.index << " (" << to_string(o.mode)
    << "): deep " << m.deep << ", missed " << m.missed << ", false rays " << m.false_rays << ", max depth error "
    << m.max_depth_error << ", over-reported contacts " << m.over_reports << " of " << m.truth_checked
    << ", deepest over the truth " << m.max_truth_ratio << "x, deepest contact " << m.deepest_ours
    << " against the overlap's deepest point " << m.deepest_exact << "\n  pose A: \"" << pose_text(m.poses.a) << "\"\n  pose B: \"" << pose_text(m.poses.b)
    << "\"\n  replay: rtcd query family:" << family.name << ":a family:" << family.name << ":b --backend "
    << o.backend << " --mode full --pose-a \"" << pose_text(m.poses.a) << "\" --pose-b \"" << pose_text(m.poses.b)
    << "\"\n  or:     rtcd validate --family " << family.name << " --backend " << o.backend << " --mode "
    << to_string(o.mode) << " --seed " << o.seed << " --pairs " << m.index + 1;
  return s.str();
}

}  // namespace rtcd::validation
