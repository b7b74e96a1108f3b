// The OpenCL backend: the step's ray work (candidate selection, compaction,
// full tracing, walks) on every chosen device, through the shared kernel
// code; on any fault, the step and those after it on the CPU executor.
#pragma once

#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "rtcd/backend.hpp"
#include "rtcd/cpu_executor.hpp"

namespace rtcd {

// The executor that finishes steps when the devices cannot: the CPU
// executor with this tracer factory.
struct CpuFallback {
  std::string name;  // the CPU backend it matches ("basic", "embree")
  std::function<std::unique_ptr<MeshTracerFactory>()> tracers;
};

// options.kind: opencl (a BVH) or opencl_basic (every ray against
// every triangle, bit for bit the CPU `basic`). Throws BackendError for a
// device index that does not exist; a missing platform or any later device
// fault is reported on stderr once and handled by `fallback`.
std::unique_ptr<NarrowPhase> make_opencl_narrow_phase(const BackendOptions& options, const Config& config,
                                                      CpuFallback fallback);

// "opencl" and "opencl-basic", with the devices they would use (name,
// compute units, memory, fp64), or why they cannot run.
std::vector<BackendInfo> opencl_backend_infos();

// Faults a test forces on narrow phases made after the call; the
// environment variable RTCD_OPENCL_FAULT (no_platform, build, out_of_memory,
// mid_step, behind_full) does the same for a whole process. mid_step strikes
// the second batch with work; behind_full the first walked batch enqueued
// behind a full batch with work, which is then still on the devices.
enum class OpenClFault { none, no_platform, build, out_of_memory, mid_step, behind_full };
void inject_opencl_fault(OpenClFault fault);
// The fault in force: the injected one, else RTCD_OPENCL_FAULT's; throws
// BackendError for a value it does not know.
OpenClFault requested_opencl_fault();

}  // namespace rtcd
