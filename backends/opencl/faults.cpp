// Faults forced on the OpenCL backend, by a test or by the environment, so
// every path to the CPU fallback runs without a broken driver.
#include <atomic>
#include <cstdlib>
#include <string>

#include "opencl_backend.hpp"
#include "rtcd/error.hpp"

namespace rtcd {
namespace {
std::atomic<OpenClFault> g_injected{OpenClFault::none};
}  // namespace

void inject_opencl_fault(OpenClFault fault) { g_injected = fault; }

OpenClFault requested_opencl_fault() {
  if (g_injected != OpenClFault::none) return g_injected;
  const char* text = std::getenv("RTCD_OPENCL_FAULT");
  if (!text || !*text) return OpenClFault::none;
  const std::string s = text;
  if (s == "no_platform") return OpenClFault::no_platform;
  if (s == "build") return OpenClFault::build;
  if (s == "out_of_memory") return OpenClFault::out_of_memory;
  if (s == "mid_step") return OpenClFault::mid_step;
  if (s == "behind_full") return OpenClFault::behind_full;
  throw BackendError("RTCD_OPENCL_FAULT='" + s +
                     "': expected no_platform, build, out_of_memory, mid_step or behind_full");
}

}  // namespace rtcd
