// Factory of the Embree 3 backend.
#pragma once

#include "rtcd/cpu_executor.hpp"

namespace rtcd {
std::unique_ptr<NarrowPhase> make_embree_narrow_phase(const Config& config);
// Its tracer, for executors that finish steps on the CPU.
std::unique_ptr<MeshTracerFactory> make_embree_tracers();
// Embree's version and ISA, for `rtcd backends`.
std::string embree_description();
}
