// What accuracy costs in time: the accuracy knobs swept one at a time around
// the default configuration, each point a differential run (time per pair
// against missed-ray rate and depth error).
#pragma once

#include <ostream>
#include <string>
#include <vector>

#include "rtcd/validation/differential.hpp"

namespace rtcd::validation {

struct SweepPoint {
  std::string knob, value;
  bool is_default = false;
  Summary summary;
};

// max walk steps, displacement threshold, distance extension, predictive
// on/off, each in iterative runs, plus the full-tracing baseline. With a
// runner, each point's shards run where it puts them, and the points come
// back on the process that reports only.
std::vector<SweepPoint> sweep(const Family& family, const std::string& backend, size_t pairs, uint64_t seed,
                              const ShardRunner* runner = nullptr);

void write_csv(std::ostream& out, const std::vector<SweepPoint>& points);

}  // namespace rtcd::validation
