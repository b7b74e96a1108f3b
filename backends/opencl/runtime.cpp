#include "runtime.hpp"

#include <cstdlib>
#include <map>
#include <mutex>
#include <sstream>

namespace rtcd::opencl_source {
extern const char* const kKernels;
}

namespace rtcd::opencl {

Selection Selection::of(const BackendOptions& options) {
  Selection s;
  s.bvh = options.kind != BackendKind::opencl_basic;
  s.type = options.device_type == DeviceType::gpu   ? CL_DEVICE_TYPE_GPU
           : options.device_type == DeviceType::cpu ? CL_DEVICE_TYPE_CPU
                                                    : CL_DEVICE_TYPE_ALL;
  for (int i : options.devices) s.indices.push_back(size_t(i));
  return s;
}

bool env_flag(const char* name) {
  const char* text = std::getenv(name);
  return text && *text && std::string(text) != "0";
}

namespace {
std::string error_name(cl_int code) {
  switch (code) {
    case CL_DEVICE_NOT_FOUND: return "CL_DEVICE_NOT_FOUND";
    case CL_MEM_OBJECT_ALLOCATION_FAILURE: return "CL_MEM_OBJECT_ALLOCATION_FAILURE (out of device memory)";
    case CL_OUT_OF_RESOURCES: return "CL_OUT_OF_RESOURCES";
    case CL_OUT_OF_HOST_MEMORY: return "CL_OUT_OF_HOST_MEMORY";
    case CL_BUILD_PROGRAM_FAILURE: return "CL_BUILD_PROGRAM_FAILURE";
    case CL_INVALID_BUFFER_SIZE: return "CL_INVALID_BUFFER_SIZE";
    case CL_EXEC_STATUS_ERROR_FOR_EVENTS_IN_WAIT_LIST: return "CL_EXEC_STATUS_ERROR_FOR_EVENTS_IN_WAIT_LIST";
    case -1001: return "CL_PLATFORM_NOT_FOUND_KHR (no OpenCL platform installed)";
    default: return "OpenCL error " + std::to_string(code);
  }
}

}  // namespace

std::string describe(const cl::Error& e) { return std::string(e.what()) + ": " + error_name(e.err()); }

Found find_devices(const Selection& s) {
  std::vector<cl::Platform> platforms;
  try {
    cl::Platform::get(&platforms);
  } catch (const cl::Error& e) {
    throw BackendError("no OpenCL platform (" + describe(e) + ")");
  }
  for (const cl::Platform& platform : platforms) {
    std::vector<cl::Device> devices;
    try {
      platform.getDevices(s.type, &devices);
    } catch (const cl::Error&) {
      continue;  // CL_DEVICE_NOT_FOUND: none of this type here
    }
    if (devices.empty()) continue;
    if (s.indices.empty()) return {platform, devices};
    Found found{platform, {}};
    for (size_t i : s.indices) {
      if (i >= devices.size())
        throw NameError("OpenCL device " + std::to_string(i) + " does not exist: " +
                        platform.getInfo<CL_PLATFORM_NAME>() + " has " + std::to_string(devices.size()));
      found.devices.push_back(devices[i]);
    }
    return found;
  }
  throw BackendError(platforms.empty() ? "no OpenCL platform" : "no OpenCL device of the requested type");
}

namespace {
bool has_fp64(const cl::Device& d) { return d.getInfo<CL_DEVICE_EXTENSIONS>().find("cl_khr_fp64") != std::string::npos; }
bool rounds_division(const cl::Device& d) {
  return (d.getInfo<CL_DEVICE_SINGLE_FP_CONFIG>() & CL_FP_CORRECTLY_ROUNDED_DIVIDE_SQRT) != 0;
}
}  // namespace

std::string describe(const cl::Platform& platform, const cl::Device& d, size_t index) {
  std::ostringstream s;
  s << '[' << index << "] " << d.getInfo<CL_DEVICE_NAME>() << " (" << platform.getInfo<CL_PLATFORM_NAME>() << "), "
    << d.getInfo<CL_DEVICE_MAX_COMPUTE_UNITS>() << " compute units, "
    << d.getInfo<CL_DEVICE_GLOBAL_MEM_SIZE>() / (1024 * 1024) << " MiB, " << (has_fp64(d) ? "fp64" : "no fp64");
  return s.str();
}

std::shared_ptr<const Runtime> acquire_runtime(const Selection& s, OpenClFault fault) {
  if (fault == OpenClFault::no_platform) throw BackendError("no OpenCL platform (injected fault)");
  const bool host_places = env_flag("RTCD_OPENCL_NO_FP64");
  std::ostringstream key;
  key << s.bvh << '/' << s.type << '/' << host_places << '/' << (fault == OpenClFault::build);
  for (size_t i : s.indices) key << ',' << i;
  static std::mutex mutex;
  // Never destroyed: releasing OpenCL objects after the driver has unloaded
  // at exit crashes some ICDs.
  static auto* cache = new std::map<std::string, std::shared_ptr<const Runtime>>;
  std::lock_guard lock(mutex);
  if (auto it = cache->find(key.str()); it != cache->end()) return it->second;

  const Found found = find_devices(s);
  auto runtime = std::make_shared<Runtime>();
  runtime->devices = found.devices;
  runtime->context = cl::Context(found.devices);
  bool rounded = true;
  for (const cl::Device& d : found.devices) {
    runtime->place_on_device = runtime->place_on_device && has_fp64(d) && !host_places;
    rounded = rounded && rounds_division(d);
  }
  // The CPU's arithmetic: OpenCL 1.2 otherwise allows a few ulp in division
  // and sqrt, which decide walks' edge tests; contraction is off in types.h.
  std::string options = "-cl-std=CL1.2";
  if (rounded) options += " -cl-fp32-correctly-rounded-divide-sqrt";
  if (s.bvh) options += " -DRTCD_BVH";
  if (!runtime->place_on_device) options += " -DRTCD_NO_FP64";
  if (fault == OpenClFault::build) options += " -DRTCD_INJECTED_BUILD_FAILURE";
  runtime->program = cl::Program(runtime->context, std::string(opencl_source::kKernels));
  try {
    runtime->program.build(found.devices, options.c_str());
  } catch (const cl::BuildError& e) {
    std::string log;
    for (const auto& [device, text] : e.getBuildLog()) log += text;
    if (log.size() > 2000) log = log.substr(0, 2000) + " ...";
    throw BackendError("the kernels failed to build with '" + options + "': " + log);
  } catch (const cl::Error& e) {
    throw BackendError("the kernels failed to build with '" + options + "': " + describe(e));
  }
  for (size_t i = 0; i < found.devices.size(); ++i) {
    std::string text = describe(found.platform, found.devices[i], s.indices.empty() ? i : s.indices[i]);
    text += runtime->place_on_device ? "; rays placed in double on the device" : "; rays placed in double on the host";
    if (!rounded) text += "; division and sqrt not correctly rounded (walks may differ from the CPU)";
    text += s.bvh ? "; BVH tracer" : "; brute-force tracer";
    runtime->descriptions.push_back(text);
  }
  (*cache)[key.str()] = runtime;
  return runtime;
}

}  // namespace rtcd::opencl
