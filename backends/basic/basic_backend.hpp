// Factory of the basic-traversal backend.
#pragma once

#include "rtcd/backend_options.hpp"
#include "rtcd/cpu_executor.hpp"

namespace rtcd {
std::unique_ptr<NarrowPhase> make_basic_narrow_phase(const BackendOptions& options, const Config& config);
// Its tracer, for executors that finish steps on the CPU.
std::unique_ptr<MeshTracerFactory> make_basic_tracers();
}
