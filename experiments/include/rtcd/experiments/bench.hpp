// `rtcd bench`: the thesis' experiments (section 2.3) on a scene. Records a
// simulation, replays it through every narrow phase, runs the accuracy
// simulations, and writes the tables (Markdown and CSV) and the data the
// plots are drawn from.
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "rtcd/sim/recording.hpp"

namespace rtcd::experiments {

// Phases of a recording, as step ranges [begin, end), defined from its
// physical quantities alone so that every configuration is judged on the
// same steps:
//   A free fall: from the first step with broad-phase pairs to the first
//     contact with the ground;
//   B impact: from there until the kinetic energy, past its peak, falls
//     below `settle_fraction` of that peak;
//   C settled: the rest.
struct Phases {
  uint64_t a_begin = 0, b_begin = 0, c_begin = 0, end = 0;
  double settle_fraction = 0.1;
  std::string rule() const;  // the definition, in words, with the steps
  char of(uint64_t step) const;  // 'A', 'B', 'C' or '-' (before A)
};
Phases find_phases(const std::vector<sim::RecordedStep>& steps, double settle_fraction = 0.1);

// The largest motion of any surface point in one step (|Δposition| plus
// rotation angle times the shape's radius), against the distance extension:
// predictive rays cannot see an impact that moves farther in a step.
struct Motion {
  double largest = 0, speed = 0;  // per step, and as a speed (largest / time step)
  uint64_t step = 0;
  uint32_t body = 0;
  std::optional<double> distance_extension;  // the scene's; unset: derived per pair
};
Motion largest_motion(const sim::Recording& recording);

struct BenchOptions {
  std::string scene;   // a scene file
  std::string replay;  // a recording to replay instead of simulating anew
  std::string out;     // the output folder
  std::string command; // where and how it ran (machine, build, command), atop the report
  uint64_t steps = 0;  // simulate this many steps instead of the scene's (0: the scene's)
  // Sampling (0: chosen from the step count, see docs/bench.md).
  uint64_t full_every = 0, peers_every = 0, judge_every = 0;
  uint32_t seeds = 3;  // simulations per interpenetration variant
  uint64_t gimpact_host_steps = 600;  // at most this many steps of the GIMPACT-hosted simulation
  double budget_seconds = 900;        // per replayed configuration (ReplayConfig::budget_seconds)
  // Stage name, done, total: for a progress bar.
  std::function<void(const std::string&, uint64_t, uint64_t)> progress;
};

// Runs everything and writes it under options.out; returns the report's path.
std::string run_bench(const BenchOptions& options);

}  // namespace rtcd::experiments
