// The registry: backends by kind, compiled in when their dependency was found.
#include <sstream>

#include "rtcd/backend.hpp"
#include "rtcd/error.hpp"
#include "basic/basic_backend.hpp"
#ifdef RTCD_WITH_EMBREE
#include "embree/embree_backend.hpp"
#endif
#ifdef RTCD_WITH_OPENCL
#include "opencl/opencl_backend.hpp"
#endif

namespace rtcd {

std::vector<BackendInfo> available_backends() {
  std::vector<BackendInfo> list;
  list.push_back({"basic", true, "cpu (TBB): every ray against every triangle"});
#ifdef RTCD_WITH_EMBREE
  try {
    list.push_back({"embree", true, embree_description()});
  } catch (const Error& e) {
    list.push_back({"embree", false, e.what()});
  }
#endif
#ifdef RTCD_WITH_OPENCL
  for (BackendInfo& info : opencl_backend_infos()) list.push_back(std::move(info));
#endif
  return list;
}

#ifdef RTCD_WITH_OPENCL
namespace {
// The CPU executor that finishes an OpenCL backend's steps after a fault:
// the same tracer as the devices' (brute force), or the fastest BVH here.
CpuFallback opencl_fallback(BackendKind kind) {
  if (kind == BackendKind::opencl_basic) return {"basic", make_basic_tracers};
#ifdef RTCD_WITH_EMBREE
  return {"embree", [] { return make_embree_tracers(); }};
#else
  return {"basic", make_basic_tracers};
#endif
}
}  // namespace
#endif

std::unique_ptr<NarrowPhase> make_narrow_phase(const BackendOptions& options, const Config& config) {
  options.validate();
  config.validate();
  const auto list = available_backends();
  auto usable = [&](BackendKind kind) {
    for (const auto& b : list)
      if (b.name == to_string(kind)) return b.usable;
    return false;
  };
  BackendOptions chosen = options;
  // A fixed order, fastest first, so a run stays reproducible.
  if (options.kind == BackendKind::automatic)
    chosen.kind = usable(BackendKind::embree)   ? BackendKind::embree
                  : usable(BackendKind::opencl) ? BackendKind::opencl
                                                : BackendKind::basic;
  switch (chosen.kind) {
    case BackendKind::basic:
      return make_basic_narrow_phase(chosen, config);
    case BackendKind::embree:
#ifdef RTCD_WITH_EMBREE
      if (usable(BackendKind::embree)) return make_embree_narrow_phase(chosen, config);
#endif
      break;
    case BackendKind::opencl:
    case BackendKind::opencl_basic:
#ifdef RTCD_WITH_OPENCL
      // Built even without a usable device: it says why and runs on the CPU.
      return make_opencl_narrow_phase(chosen, config, opencl_fallback(chosen.kind));
#endif
      break;
    case BackendKind::automatic:
      break;
  }
  std::ostringstream s;
  s << "backend '" << options.to_string() << "' is not available; available:";
  for (const auto& b : list) s << ' ' << b.name << (b.usable ? "" : " (unusable: " + b.detail + ")");
  s << " auto";
  throw BackendError(s.str());
}

std::unique_ptr<NarrowPhase> make_narrow_phase(std::string_view name, const Config& config) {
  return make_narrow_phase(BackendOptions::parse(name), config);
}

}  // namespace rtcd
