// Where a run's rays ran, for a device backend: each device's rays summed
// over the steps, and the first step that fell back to the CPU, with why.
#pragma once

#include <algorithm>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace rtcd::app {

struct DeviceShare {
  std::vector<size_t> rays;             // by device; empty on the CPU backends
  std::optional<uint64_t> fallback_step;
  std::string fallback_reason;

  void add(uint64_t step, const std::vector<size_t>& device_rays, const std::string& cpu_fallback) {
    rays.resize(std::max(rays.size(), device_rays.size()));
    for (size_t d = 0; d < device_rays.size(); ++d) rays[d] += device_rays[d];
    if (!fallback_step && !cpu_fallback.empty()) {
      fallback_step = step;
      fallback_reason = cpu_fallback;
    }
  }
};

}  // namespace rtcd::app
