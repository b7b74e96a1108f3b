// `rtcd bench SCENE`: the thesis' experiments on a scene (docs/bench.md).
#pragma once

#include <cstdint>
#include <string>

namespace rtcd::cli {

struct BenchOptions {
  std::string scene;   // a file, or a name under data/scenes ("avalanche")
  std::string replay;  // a recording to replay instead of simulating anew
  std::string out;     // default: runs/bench-<scene>-<timestamp>/
  uint64_t full_every = 0, peers_every = 0, judge_every = 0, gimpact_host_steps = 600;
  double budget_seconds = 900;
  uint32_t seeds = 3;
  uint64_t steps = 0;  // 0: the scene's
  bool no_plots = false;
  std::string command;  // the command line as typed
};

// Exit 0 done, 2 bad input.
int run_bench(const BenchOptions& options);

}  // namespace rtcd::cli
