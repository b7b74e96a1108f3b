// Replays a recorded simulation through several narrow phases in lockstep:
// at every step each configuration sees the same poses and the same
// broad-phase pairs. Ours (any backend, mode and knobs, on a chosen number
// of threads), Bullet's GIMPACT and FCL; rays of ours judged against the
// exact reference on sampled steps.
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "rtcd/backend.hpp"
#include "rtcd/config.hpp"
#include "rtcd/results.hpp"
#include "rtcd/sim/recording.hpp"

namespace rtcd::experiments {

enum class Engine {
  ours,     // make_narrow_phase(backend, config)
  gimpact,  // btGImpactMeshShape pairs through btGImpactCollisionAlgorithm, every penetrating point
  fcl,      // fcl::collide on BVHModel<OBBRSS> meshes, every contact
};
const char* to_string(Engine engine);

struct ReplayConfig {
  std::string label;  // "auto embree", "GIMPACT", ...
  Engine engine = Engine::ours;
  std::string backend = "embree";
  Config config;
  int threads = 1;
  // Replayed on steps 0, every, 2 every, ... only. Stateless configurations
  // alone may skip steps: iterative and automatic ones carry pair state.
  uint64_t every = 1;
  // Once its steps have taken this many seconds in all, the configuration
  // stops for the rest of the replay (0: never). Keeps a slow tracer from
  // holding up a long scene; the report says where it stopped.
  double budget_seconds = 0;
  bool stateless() const { return engine != Engine::ours || config.mode == Mode::full; }
};

struct ReplayStep {
  bool ran = false;
  double seconds = 0;  // the whole query: detect, or every pair's collide
  // Ours: where detect spent it (StepStats); full + iterative is the ray
  // time, tracing and walking, what the thesis timed.
  double seconds_prepare = 0, seconds_full = 0, seconds_iterative = 0, seconds_gather = 0;
  double seconds_rays() const { return seconds_full + seconds_iterative; }
  size_t pairs = 0, colliding = 0, contacts = 0;
  size_t predictive = 0;  // ours: predictive rays reported
  size_t pairs_full = 0, pairs_iterative = 0;
  size_t fallbacks = 0;  // of pairs_full, those equation 2.1 sent back (the rest are new)
  // Ours: pairs skipped on a certificate, certificates granted, expired (StepStats).
  size_t pairs_certified = 0, certificates_granted = 0, certificates_expired = 0;
  RayCounts counts;       // ours: the step's rays by what they did (kRayCounters)
  double depth_sum = 0;  // summed depth of every contact as the engine reports it
  // Ours: a digest of every contact's bodies, kind, vertex or edge and face,
  // in order (FNV-1a): equal digests, the same contacts.
  uint64_t contact_digest = 0;
  std::vector<DeviceWork> devices;  // ours on OpenCL: what each device did (StepStats::devices)
  std::string cpu_fallback;         // ours on OpenCL: why the step ran on the CPU instead; empty: it did not
  // Judged steps (ours): ray origins the exact reference puts deeper than
  // epsilon inside the other body, and of those the ones with no contact;
  // contacts whose origin it puts farther than epsilon outside (false rays);
  // pairs it finds interpenetrating deeper than epsilon (a vertex, an edge
  // crossing, a sphere's cap) that we call separate; contacts judged against
  // the true penetration at their point, and those over it
  // (oracle::over_reports).
  bool judged = false;
  size_t deep = 0, missed = 0, false_rays = 0, missed_pairs = 0, truth_checked = 0, over_reports = 0;
};

struct ReplayRun {
  ReplayConfig config;
  std::string engine_name;  // the backend's name, or the library's
  std::vector<ReplayStep> steps;  // one per recorded step
  uint64_t stopped_at = UINT64_MAX;  // the first step it skipped for its budget
  bool stopped() const { return stopped_at != UINT64_MAX; }
};

struct ReplayOptions {
  uint64_t judge_every = 0;     // 0: never
  double epsilon_scale = 1e-5;  // no claim on origins this close (times the larger radius) to the surface
  // Called after each step with (steps done, steps in all).
  std::function<void(uint64_t, uint64_t)> progress;
  // Called after each step with the result of the first configuration of
  // ours that ran it (its contacts, pairs and counters).
  std::function<void(uint64_t, const StepResult&)> observe;
};

// Throws UsageError for a configuration that cannot be replayed (a stateful
// one sampled, an unknown backend).
std::vector<ReplayRun> replay(const sim::Recording& recording, const std::vector<ReplayConfig>& configs,
                              const ReplayOptions& options = {});

}  // namespace rtcd::experiments
