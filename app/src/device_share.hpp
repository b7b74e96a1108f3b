// Where a run's rays ran, for a device backend: each device's rays summed
// over the steps, and the first step that fell back to the CPU, with why.
#pragma once

#include <algorithm>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "rtcd/results.hpp"

namespace rtcd::app {

struct DeviceShare {
  std::vector<size_t> rays;             // by device; empty on the CPU backends
  std::optional<uint64_t> fallback_step;
  std::string fallback_reason;

  void add(uint64_t step, const std::vector<DeviceWork>& devices, const std::string& cpu_fallback) {
    rays.resize(std::max(rays.size(), devices.size()));
    for (size_t d = 0; d < devices.size(); ++d) rays[d] += devices[d].rays;
    if (!fallback_step && !cpu_fallback.empty()) {
      fallback_step = step;
      fallback_reason = cpu_fallback;
    }
  }
};

}  // namespace rtcd::app
