// `rtcd replay RECORDING`: one narrow-phase configuration on a recorded
// trajectory (the poses and broad-phase pairs of every step), with where
// each phase's time goes — in seconds, not a bench's quarter hour.
#pragma once

#include <string>

#include "rtcd/app/inputs.hpp"

namespace rtcd::app {

struct ReplayOptions {
  std::string recording;
  std::string peer;  // "gimpact" or "fcl": that library on the same steps instead of rtcd
  std::string backend = "embree";
  std::string mode = "auto";
  int threads = 1;
  uint64_t judge_every = 0;  // 0: no step judged
  uint64_t last = 0;         // > 0: a row for the recording's last steps too (a stream never settles)
  Knobs knobs;               // set ones replace the recorded scene's
};

// Prints the table; exit 0 done, 2 bad input.
int run_replay(const ReplayOptions& options);

}  // namespace rtcd::app
