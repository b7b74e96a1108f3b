// The step pipeline every backend runs on. The host side — pair state,
// equation 2.1, the overlap boxes, depth refinement, contacts, pair summaries
// and statistics — is written once here; a backend is a RayExecutor that
// turns a batch of pair-directions into one outcome per candidate ray, where
// its data lives (CPU threads now, devices later).
#pragma once

#include <array>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "rtcd/criterion.hpp"
#include "rtcd/kernel/classify.h"
#include "rtcd/kernel/tally.h"
#include "rtcd/kernel/tracer.h"
#include "rtcd/limits.hpp"
#include "rtcd/narrow_phase.hpp"

namespace rtcd {

// What one candidate ray found: the kernel's record (kernel/tracer.h), so
// executors write it where the rays run and the host reads it as it is. `t`
// is the kernel's float distance; the host refines reported rays in double.
// A step's kept outcomes are also the pair-direction's tracked rays, the
// walks' start for the next step (vertex, `triangle`: the exit face or where
// the walk starts, -1 for a watched vertex whose nearest triangle is looked
// up when the pair walks; `entry`: a penetrating ray's entry face, -1
// unknown). The host keeps them with the pair's state, so any executor can
// take over a pair without tracing it again; an executor that keeps them
// where they ran may leave placeholders there (RayExecutor::recover).
using RayOutcome = rtcd_outcome;

// Where an executor ran a pair-direction and left its tracked rays after a
// step (on a device, say), so the next step's walks run there without
// sending them again, and the pair stays there. The executor's own note:
// the pipeline keeps it with the pair's state and drops it with that state;
// when the rays there no longer match the pair's (drop_rays), the place stays.
struct Residence {
  uint64_t step = 0;    // the executor's step (begin_step) that wrote the rays; 0: none
  uint32_t place = 0;   // where, in the executor's numbering (a device)
  uint32_t first = 0;   // the first of the rays there
  uint32_t count = 0;   // how many: the first `count` kept outcomes
  bool placed = false;  // the pair-direction has run at `place`
  uint32_t reports = 0;  // placed: the contacts and predictive rays it made there last
  uint32_t slot = kNoRecord;  // the executor's record of the pair there (a device's pair-table row)

  static constexpr uint32_t kNoRecord = 0xffffffffu;

  void drop_rays() { step = 0; }
};

// One direction of one pair: the source's rays against the target.
struct RayJob {
  ShapeId source = 0, target = 0;
  BodyId source_body = 0, target_body = 0;  // whose poses make the frame (rtcd_relative_frame)
  // Source frame to target frame, in double: rays are cast in the target's
  // local frame, where its acceleration structure lives and where bodies far
  // from the world origin keep their relative precision.
  Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();
  Eigen::Vector3d translation = Eigen::Vector3d::Zero();
  // Candidate origins lie in this box (target frame); empty: no candidates.
  Aabb overlap;
  bool iterative = false;
  bool edges = true;  // this direction tests its source's edges (Config::edge_contacts permitting)
  PairLimits limits;
  // Iterative jobs: how far a point of the source may have moved relative
  // to the target since the pair's last full step (equation 2.1); a watched
  // edge farther from the surface than this needs no test yet.
  double moved = 0.0;
  // The pair's motion in the last step, from which its limits were derived
  // (derive_limits' m; 0 when the Config sets every limit).
  double motion = 0.0;
  // The motion is equation 2.1 from the bodies' poses of the last step
  // (begin_step's, one step before) to this step's; else it is 0.
  bool motion_measured = false;
  // Iterative jobs: last step's kept outcomes, the walks' start triangles.
  std::span<const RayOutcome> tracked;
  // The pair-direction's note for the executor, read and written by it;
  // null: none is kept.
  Residence* residence = nullptr;
};

// A job's rays summed up: its records (contacts, predictive rays) and its
// share of the step's statistics.
struct RayTally : RayCounts {
  size_t contacts = 0, predictive = 0;

  // Outcomes counted by the executors' one rule (kernel/tally.h).
  RayTally& operator+=(const rtcd_tally& counted);
  // A held watched edge, still tracked (Config::edge_retest_motion).
  void hold() {
    ++edges_held;
    ++rays_watched;
  }
  // Where the job's rays ran, in the executor's numbering (a device); -1:
  // on the CPU. Not summed.
  int32_t place = -1;

  RayTally& operator+=(const RayTally& other);
};

// Counts a job's outcomes, then removes those that neither report nor track
// anything (RTCD_RAY_DROPPED), keeping the others in order. Executors call
// it on each job's outcomes once they are final, on the thread that wrote
// them: the counting then runs on every executor thread at once instead of
// in a pass of the host's, and the host reads only the kept outcomes (most
// candidates of a full step are dropped).
RayTally settle_outcomes(std::vector<RayOutcome>& outcomes, bool iterative);

// One of a step's two batches (Algorithm 2): the pair-directions traced in
// full, or those walked from last step's rays; the pipeline never mixes the
// two. Jobs 2i and 2i + 1 are one pair's two directions. Job j's outcomes
// and tally are at index j beside it.
struct RayBatch {
  bool iterative = false;
  std::vector<RayJob> jobs;
  std::vector<std::vector<RayOutcome>> outcomes;
  std::vector<RayTally> tallies;
  // What an executor counted on its own (a device reduces its outcomes
  // there), beside its jobs' tallies, which then hold only their records.
  // Cleared by the pipeline before each step's batches.
  RayCounts counted;

  // `count` jobs, their outcome buffers kept from earlier steps.
  void resize(size_t count) {
    jobs.resize(count);
    if (outcomes.size() < count) outcomes.resize(count);
    if (tallies.size() < count) tallies.resize(count);
  }
};

// A box as kernel/frame.h takes it.
inline rtcd_box to_kernel(const Aabb& box) {
  return {{box.min.x(), box.min.y(), box.min.z()}, {box.max.x(), box.max.y(), box.max.z()}};
}

class RayExecutor {
 public:
  virtual ~RayExecutor() = default;
  // Called once, before anything else: the configuration every batch runs
  // with (the per-pair limits come with each job).
  virtual void configure(const Config& config) = 0;
  // Called once per shape, in ShapeId order, before any job names it, with
  // its scale (measured only when some limit is derived), for an executor
  // that derives the jobs' limits where it runs them (rtcd_derive_limits).
  virtual void add_shape(std::shared_ptr<const Shape> shape, const ShapeScale& scale) = 0;
  // Called once per body, in BodyId order, with its shape, for an executor
  // that keeps the bodies' shapes where it runs the jobs.
  virtual void add_body(ShapeId /*shape*/) {}
  // Called before each step's batches: a residence is good for the step
  // after the one that wrote it. `poses`: every body's pose by BodyId, the
  // step's, for an executor that makes the jobs' frames where it runs them
  // (rtcd_relative_frame, the bits of RayJob's); valid until the step ends.
  virtual void begin_step(std::span<const rtcd_pose> /*poses*/) {}
  // Job j of the batch: its candidates, in order — every source item the overlap box takes
  // (rtcd_place_item: origins with a direction inside it, then edges that
  // meet it; full jobs, by item), or every tracked item it takes (iterative
  // jobs, in tracked order) — each traced, walked or (edges) tested to one
  // outcome; a ray that reports nothing has kind
  // RTCD_RAY_DROPPED, or RTCD_RAY_WATCHED when it stays tracked (its
  // `triangle` is where the next walk starts). batch.outcomes[j] and
  // batch.tallies[j] receive what settle_outcomes makes of them; the
  // executor only clears and fills them. An executor that counts on its
  // own (a device) leaves only the records (contacts, predictive) in the
  // tallies and adds the counters into batch.counted; an executor that
  // keeps the tracked rays where they ran (a device, the job's residence)
  // may fill a kept outcome that reports nothing with its kind and edge
  // alone, a placeholder whose walk start (vertex, triangle, entry) only
  // recover gives. Each step executes its full batch,
  // then its walked one; the full batch's outcomes may be left to be filled
  // by the walked batch's call (an executor that runs both at once, as a
  // device does, waits for them together).
  virtual void execute(RayBatch& batch) = 0;
  // Before the next step's batches (begin_step): the walk starts of a
  // pair-direction's kept outcomes, where this step left placeholders, so
  // the host can reorder, copy or hand them elsewhere. `tracked` is the
  // direction's kept outcomes as execute left them, `residence` its note.
  // Executors that deliver whole outcomes have nothing to do.
  virtual void recover(const Residence& /*residence*/, std::span<RayOutcome> /*tracked*/) {}
  // After the step's batches: where its rays ran and what moving them took
  // (StepStats::devices, their sums, ::cpu_fallback), so a host or a test
  // can tell a device's work from a fallback's. The CPU executors have
  // nothing to add.
  virtual void account(StepStats& /*stats*/) const {}
};

// `threads` > 0: the narrow phase's steps run in a TBB arena of its own
// with that many threads; 0: in the caller's.
std::unique_ptr<NarrowPhase> make_pipeline_narrow_phase(std::string name, std::vector<std::string> devices,
                                                        std::unique_ptr<RayExecutor> executor, const Config& config,
                                                        int threads = 0);

}  // namespace rtcd
