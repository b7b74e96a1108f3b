// Factory of the Embree 3 backend, optionally with Embree's instruction set
// pinned (BackendOptions::isa).
#pragma once

#include <string>

#include "rtcd/backend_options.hpp"
#include "rtcd/cpu_executor.hpp"

namespace rtcd {
// Throws BackendError for an unknown instruction set, or one this CPU does
// not run.
std::unique_ptr<NarrowPhase> make_embree_narrow_phase(const BackendOptions& options, const Config& config);
// Its tracer, for executors that finish steps on the CPU; `isa` empty:
// Embree's own choice.
std::unique_ptr<MeshTracerFactory> make_embree_tracers(const std::string& isa = "");
// Embree's version (and the pinned instruction set), for `rtcd backends`.
std::string embree_description(const std::string& isa = "");
}  // namespace rtcd
