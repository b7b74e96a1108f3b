// Factory of the basic-traversal backend.
#pragma once

#include "rtcd/cpu_executor.hpp"

namespace rtcd {
std::unique_ptr<NarrowPhase> make_basic_narrow_phase(const Config& config);
}
