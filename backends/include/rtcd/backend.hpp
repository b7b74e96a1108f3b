// Choosing a backend at run time: the registry that makes a narrow phase
// from a typed description of the backend (rtcd/backend_options.hpp).
#pragma once

#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "rtcd/backend_options.hpp"
#include "rtcd/config.hpp"
#include "rtcd/export.hpp"
#include "rtcd/narrow_phase.hpp"

namespace rtcd {
RTCD_PUBLIC_BEGIN

struct BackendInfo {
  std::string name;
  bool usable = false;
  std::string detail;  // devices, or why it cannot run here
};

// Backends built into this library, usable or not.
std::vector<BackendInfo> available_backends();

// Throws BackendError listing what is available, or naming the option or
// device that is wrong; ConfigError for a bad configuration. name() of the
// result is options.name() with `automatic` resolved.
std::unique_ptr<NarrowPhase> make_narrow_phase(const BackendOptions& options, const Config& config = {});
// The same from the string form (BackendOptions::parse).
std::unique_ptr<NarrowPhase> make_narrow_phase(std::string_view name, const Config& config = {});

RTCD_PUBLIC_END
}  // namespace rtcd
