// The OpenCL backend: the step's ray work (candidate selection, compaction,
// full tracing, walks) on every chosen device, through the shared kernel
// code; on any fault, the step and those after it on the CPU executor.
#pragma once

#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "rtcd/cpu_executor.hpp"

namespace rtcd {

// Registry names: "opencl" (stackless BVH) or "opencl-basic" (every ray
// against every triangle, bit for bit the CPU `basic`), optionally followed
// by ":gpu", ":cpu" (device type) and ":devices=0,1" (device indices on the
// first platform that has devices of that type). Default: every device of
// the first platform with any.
bool is_opencl_name(const std::string& name);

// The executor that finishes steps when the devices cannot: the CPU
// executor with this tracer factory.
struct CpuFallback {
  std::string name;  // the CPU backend it matches ("basic", "embree")
  std::function<std::unique_ptr<MeshTracerFactory>()> tracers;
};

// Throws BackendError for a name it cannot parse or a device index that
// does not exist; a missing platform or any later device fault is reported
// on stderr once and handled by `fallback`.
std::unique_ptr<NarrowPhase> make_opencl_narrow_phase(const std::string& name, const Config& config,
                                                      CpuFallback fallback);

// "opencl" and "opencl-basic", with the devices they would use (name,
// compute units, memory, fp64), or why they cannot run.
std::vector<BackendInfo> opencl_backend_infos();

// Faults a test forces on narrow phases made after the call; the
// environment variable RTCD_OPENCL_FAULT (no_platform, build, out_of_memory,
// mid_step) does the same for a whole process.
enum class OpenClFault { none, no_platform, build, out_of_memory, mid_step };
void inject_opencl_fault(OpenClFault fault);

}  // namespace rtcd
