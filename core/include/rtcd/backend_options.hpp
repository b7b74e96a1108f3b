// A backend described by type, not by a string: which kind, on which
// devices, with how many threads; and the string form that the CLI and
// scene files write ("opencl:gpu:devices=0,1"), read and written here only.
#pragma once

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "rtcd/export.hpp"

namespace rtcd {
RTCD_PUBLIC_BEGIN

enum class BackendKind : uint8_t {
  automatic,     // the fastest usable one, in a fixed order: embree, opencl, basic
  basic,         // CPU threads, every ray against every triangle
  embree,        // CPU threads, Embree's BVH
  opencl,        // OpenCL devices, a BVH
  opencl_basic,  // OpenCL devices, every ray against every triangle (bit for bit `basic`)
};
// "auto", "basic", "embree", "opencl", "opencl-basic".
const char* to_string(BackendKind kind);

enum class DeviceType : uint8_t { any, gpu, cpu };
// How an OpenCL backend lays a batch's items on the devices: compacted
// candidates (two round trips), a grid of every item (one), or grid for
// iterative batches and compacted for full ones (docs/results/opencl.md).
enum class DeviceLayout : uint8_t { by_mode, grid, compact };

struct BackendOptions {
  BackendKind kind = BackendKind::automatic;
  // Threads a step may use: the narrow phase's own TBB arena, so two narrow
  // phases in one process do not limit each other. 0: the caller's.
  int threads = 0;
  // embree: the instruction set Embree is pinned to (sse2, sse4.2, avx,
  // avx2, avx512), so a run replays on another machine with the same
  // kernels; empty: Embree's own choice.
  std::string isa;
  // opencl, opencl_basic: the first platform with devices of this type,
  // the devices by index there (empty: all of them), the batch layout.
  DeviceType device_type = DeviceType::any;
  std::vector<int> devices;
  DeviceLayout layout = DeviceLayout::by_mode;

  // The string form: a kind, then options after ':' — threads=N on every
  // kind; isa=NAME on embree; gpu, cpu, devices=0,1, layout=grid or
  // layout=compact on opencl and opencl-basic. Throws BackendError naming
  // the part it does not know.
  static BackendOptions parse(std::string_view text);
  // The string form parse reads back, options in a fixed order.
  std::string to_string() const;
  // The string form less the thread count: which backend, not how many
  // threads it was given (NarrowPhase::name()).
  std::string name() const;
  // Throws BackendError for an option the kind does not take.
  void validate() const;
};

RTCD_PUBLIC_END
}  // namespace rtcd
