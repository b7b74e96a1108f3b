// Factory of the Embree 3 backend.
#pragma once

#include "rtcd/cpu_executor.hpp"

namespace rtcd {
std::unique_ptr<NarrowPhase> make_embree_narrow_phase(const Config& config);
// Embree's version and ISA, for `rtcd backends`.
std::string embree_description();
}
