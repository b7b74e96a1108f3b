// OpenCL devices and the runtime built for them: which devices a backend's
// options choose, their descriptions, and one context and built program per
// device set, shared by the narrow phases of a process.
#pragma once

#include <CL/opencl.hpp>

#include <memory>
#include <string>
#include <vector>

#include "opencl_backend.hpp"
#include "rtcd/backend.hpp"
#include "rtcd/error.hpp"

namespace rtcd::opencl {

// A bad device index: the caller's mistake, not a fault to survive.
class NameError : public BackendError {
 public:
  using BackendError::BackendError;
};

// The devices a backend's options choose.
struct Selection {
  bool bvh = true;
  cl_device_type type = CL_DEVICE_TYPE_ALL;
  std::vector<size_t> indices;  // empty: every device

  static Selection of(const BackendOptions& options);
};

std::string describe(const cl::Error& e);

struct Found {
  cl::Platform platform;
  std::vector<cl::Device> devices;
};

// The first platform with devices of the selection's type, and the chosen
// ones among them. BackendError when there are none; NameError for an index
// past the platform's devices.
Found find_devices(const Selection& s);

// "[index] name (platform), compute units, memory, fp64".
std::string describe(const cl::Platform& platform, const cl::Device& d, size_t index);

// A context and a built program for a device set, shared by every narrow
// phase of the process that asks for the same set (building takes long).
struct Runtime {
  cl::Context context;
  std::vector<cl::Device> devices;
  cl::Program program;
  bool place_on_device = true;  // every device has fp64: rays are placed there
  std::vector<std::string> descriptions;
};

std::shared_ptr<const Runtime> acquire_runtime(const Selection& s, OpenClFault fault);

// An environment variable set to anything but "" or "0".
bool env_flag(const char* name);

}  // namespace rtcd::opencl
