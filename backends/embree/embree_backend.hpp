// Factory of the Embree 3 backend: "embree", or "embree:isa=NAME" with
// Embree's instruction set pinned (sse2, sse4.2, avx, avx2, avx512), so a
// run replays on another machine with the same kernels.
#pragma once

#include <string>

#include "rtcd/cpu_executor.hpp"

namespace rtcd {
bool is_embree_name(const std::string& name);
// Throws BackendError for an unknown option or instruction set, or one this
// CPU does not run.
std::unique_ptr<NarrowPhase> make_embree_narrow_phase(const std::string& name, const Config& config);
// Its tracer, for executors that finish steps on the CPU; `isa` empty:
// Embree's own choice.
std::unique_ptr<MeshTracerFactory> make_embree_tracers(const std::string& isa = "");
// Embree's version (and the pinned instruction set), for `rtcd backends`.
std::string embree_description(const std::string& isa = "");
}  // namespace rtcd
