// Differential validation: run a backend over many random pairs of a family
// and judge every ray and every pair against the exact reference; FCL,
// GIMPACT and (convex families) libccd run on the same pairs and judge the
// exact reference (their agreement with it), not the backend. Per-pair
// metrics, family aggregates and the time per pair of each.
#pragma once

#include <cstdint>
#include <limits>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include <nlohmann/json_fwd.hpp>

#include "rtcd/config.hpp"
#include "rtcd/oracle/exact.hpp"
#include "rtcd/results.hpp"
#include "rtcd/validation/families.hpp"

namespace rtcd::validation {

enum class RunMode {
  full,       // one full step at the drawn poses
  iterative,  // a full step, then motion_steps steps of Family::step_motion(), the last one judged
};
const char* to_string(RunMode mode);
RunMode parse_run_mode(const std::string& text);  // UsageError otherwise

struct RunOptions {
  std::string backend = "auto";
  RunMode mode = RunMode::full;
  size_t pairs = 1000;
  uint64_t seed = 1;
  Config config;  // mode is set from `mode`; the other knobs are used as given
  // Vertices within epsilon = epsilon_scale * (larger radius) of the
  // surface are neither "deep" nor "far": no claim is made about them.
  double epsilon_scale = 1e-5;
  bool with_oracles = true;  // FCL, GIMPACT, libccd (the exact reference always runs)
  // GIMPACT takes up to a second per pair on the 20k-triangle family: it
  // runs on the first `gimpact_pairs` pairs only.
  size_t gimpact_pairs = std::numeric_limits<size_t>::max();
  bool single_thread = true;  // our backend on one thread, as the oracles run
  // Iterative runs: steps after the full one, each moving B by the family's
  // step_motion() (the same way each time). A fixed physical motion, so a
  // smaller displacement threshold buys accuracy with full steps, never by
  // shrinking the test.
  size_t motion_steps = 4;
};

struct PairMetrics {
  uint64_t index = 0;
  PosePair poses;  // where it was judged (after the motions in iterative runs)
  bool iterative = false;  // the judged step walked (iterative runs)
  bool certified = false;  // ... or was skipped on a certificate (PairMode::certified)
  size_t full_steps = 0;   // iterative runs: of the motion steps, those equation 2.1 sent back to full
  size_t deep = 0;         // origins the exact reference puts inside deeper than epsilon
  size_t missed = 0;       // ... with no penetrating ray
  size_t missed_untracked = 0;  // ... of those, no ray was tracked for going into the judged step (iterative runs)
  size_t far_outside = 0;  // origins outside by more than epsilon
  size_t false_rays = 0;   // penetrating rays from those
  size_t depth_checked = 0;
  double max_depth_error = 0.0, max_relative_depth_error = 0.0;
  size_t inside_any = 0;   // origins inside at any depth, both directions
  size_t crossing_deep = 0;  // edges crossing the other body with neither end inside (or a sphere's cap), deeper than epsilon
  size_t crossing_any = 0;   // ... at any depth
  bool colliding_exact = false;  // some origin or edge crossing deeper than epsilon
  bool colliding_ours = false;
  bool contained = false;  // every origin of one body inside the other
  bool fcl = false, has_gimpact = false, gimpact = false;
  bool has_ccd = false, ccd = false;
  double ccd_depth = 0.0, our_projected_depth = 0.0;
  // Contacts judged against the true penetration, those deeper than it
  // allows (Summary::over_reports), and the largest solver depth over it.
  size_t truth_checked = 0, over_reports = 0;
  double max_truth_ratio = 0.0;
  // Truth from below: the deepest point of the overlap the exact reference
  // finds (an origin's distance to the surface, the deepest middle of an
  // edge's pieces inside; a sphere's cap depth is how far it reaches in, no
  // point's depth, and is left out) and our deepest contact; under-reported
  // when that is under 0.8x the exact one less 1e-3 of the smaller body's
  // radius.
  double deepest_exact = 0.0, deepest_ours = 0.0;
  bool under_reported = false;
  // What the pair adds to the run's means and percentiles, kept with it so
  // that a run cut into shards folds to the same summary (summarize()):
  // the summed depth errors, each contact's solver depth over the truth and
  // push angle (those deeper than epsilon), the references' seconds.
  double depth_error_sum = 0.0;
  std::vector<double> truth_ratios, push_angles;
  double seconds_exact = 0.0, seconds_fcl = 0.0, seconds_fcl_contacts = 0.0, seconds_gimpact = 0.0,
         seconds_ccd = 0.0;
  double missed_rate() const { return deep ? double(missed) / double(deep) : 0.0; }
  bool missed_pair() const { return colliding_exact && !colliding_ours; }
  // rtcd calls it colliding with nothing of either body in the other at any depth.
  bool false_pair() const { return colliding_ours && inside_any == 0 && crossing_any == 0; }
};

struct Summary {
  std::string family, backend;
  RunMode mode = RunMode::full;
  Config config;  // the knobs the backend ran with
  size_t pairs = 0;
  uint64_t seed = 0;
  double epsilon = 0.0;
  size_t iterative_pairs = 0, certified_pairs = 0;  // judged steps that walked, that were skipped on a certificate
  size_t motion_steps = 0, full_steps = 0;  // iterative runs: pair-steps after the first, and those traced in full
  bool with_oracles = false;  // FCL, GIMPACT, libccd ran: their fields mean something
  size_t deep = 0, missed = 0, missed_untracked = 0, far_outside = 0, false_rays = 0, depth_checked = 0;
  double max_depth_error = 0.0, max_relative_depth_error = 0.0, mean_depth_error = 0.0;
  double missed_p50 = 0.0, missed_p90 = 0.0, missed_p99 = 0.0, missed_max = 0.0;  // per colliding pair
  size_t colliding = 0;  // by the exact reference
  size_t fcl_checked = 0, fcl_agree = 0;  // pairs with a deep origin, one body not wholly inside the other
  size_t contained = 0, fcl_blind_contained = 0;  // wholly inside; of those FCL calls separated
  // Pairs the exact reference calls colliding (an origin or an edge
  // crossing deeper than epsilon) that rtcd calls separate; of those, the
  // ones FCL calls colliding; pairs rtcd calls colliding with nothing of
  // either body inside the other at any depth; pairs colliding only through
  // edge crossings (no origin deeper than epsilon).
  size_t missed_pairs = 0, fcl_missed_pairs = 0, false_pairs = 0, crossing_pairs = 0;
  // Pairs FCL calls colliding and rtcd separate where the exact reference
  // finds nothing deeper than epsilon (touching, within the tolerance).
  size_t fcl_touching_pairs = 0;
  // The judged step's work: rays from origins (full traces, predictive
  // rays, walks) and the edges' rays, and edges tested.
  size_t vertex_rays = 0, edge_rays = 0, edges_tested = 0;
  size_t gimpact_runs = 0, gimpact_checked = 0, gimpact_agree = 0;
  // Every contact against the true penetration: the exact distance from
  // its point to the target's nearest surface (closed targets). The depth
  // the solver receives (the push's length) over the truth, for contacts
  // deeper than epsilon; contacts deeper than 1.25x the truth + 1e-3 of the smaller body's radius; the
  // angle between the push and the way to the nearest surface point.
  size_t truth_checked = 0, over_reports = 0;
  size_t under_reported_pairs = 0;  // PairMetrics::under_reported
  double truth_ratio_p50 = 0.0, truth_ratio_p99 = 0.0, truth_ratio_max = 0.0;
  double push_angle_p50 = 0.0, push_angle_p95 = 0.0;  // degrees
  size_t ccd_pairs = 0;
  double ccd_mean_abs_difference = 0.0, ccd_mean_ratio = 0.0;  // our largest projected depth vs libccd's
  // Seconds per pair (FCL: boolean collide, and collide with every contact).
  // Ours in iterative runs: per pair and step, over the motion steps.
  double time_ours = 0.0, time_exact = 0.0, time_fcl = 0.0, time_fcl_contacts = 0.0, time_gimpact = 0.0,
         time_ccd = 0.0;

  double missed_rate() const { return deep ? double(missed) / double(deep) : 0.0; }
  double colliding_fraction() const { return pairs ? double(colliding) / double(pairs) : 0.0; }
  double fcl_agreement() const { return fcl_checked ? double(fcl_agree) / double(fcl_checked) : 1.0; }
  double missed_pair_rate() const { return colliding ? double(missed_pairs) / double(colliding) : 0.0; }
  double gimpact_agreement() const { return gimpact_checked ? double(gimpact_agree) / double(gimpact_checked) : 1.0; }
};

struct RunResult {
  Summary summary;
  std::vector<PairMetrics> pairs;
};

// The pairs [first, first + pairs.size()) of a run, stepped by our backend
// in one batch and judged. Each pair's poses depend on the seed, the family
// and its index alone, so any cut of a run into shards judges the same pairs
// the same way.
struct Shard {
  size_t first = 0;
  std::string backend;  // the name the backend gave itself
  std::vector<PairMetrics> pairs;
  size_t vertex_rays = 0, edge_rays = 0, edges_tested = 0;  // the judged step's work
  double seconds_ours = 0.0;                                // our timed steps
};

Shard run_shard(const Family& family, const RunOptions& options, size_t first, size_t count);

// A run's summary from all of its shards, given in pair order: one fold over
// the pairs, so every count, rate and bound is the same however the run was
// cut (the seconds are summed over the shards). Throws UsageError when
// the shards do not cover the run's pairs exactly once, in order.
RunResult summarize(const Family& family, const RunOptions& options, std::span<const Shard> shards);

// The whole run in one shard.
RunResult run_family(const Family& family, const RunOptions& options);

// Where a run's shards run and how it is cut: across the ranks of an MPI
// job, or into a campaign's directory (rtcd::app).
class ShardRunner {
 public:
  virtual ~ShardRunner() = default;
  // Every shard of the run in pair order on the process that reports;
  // nothing on the others, and nothing when the run was stopped unfinished.
  virtual std::optional<std::vector<Shard>> run(const Family& family, const RunOptions& options) const = 0;
};

// run_family with the shards run where `runner` puts them: the summary on
// the process that reports, nothing elsewhere.
std::optional<RunResult> run_family(const Family& family, const RunOptions& options, const ShardRunner& runner);

// A shard as JSON, every double exactly, and back (UsageError naming
// what is missing or malformed).
nlohmann::json to_json(const Shard& shard);
Shard shard_from_json(const nlohmann::json& json);

nlohmann::json to_json(const Summary& summary);
// The angle (degrees) between a contact's push and the way from its point
// to the target's nearest surface point, `truth` away; where several are as
// near (the middle of a slab), the one the contact names if it is one of
// them.
double push_angle(const Contact& contact, const oracle::ExactShape& target, const Pose& target_pose, double truth,
                  double epsilon);

// One pair at full precision, and the command that replays it.
std::string describe(const Family& family, const PairMetrics& pair, const RunOptions& options);

}  // namespace rtcd::validation
