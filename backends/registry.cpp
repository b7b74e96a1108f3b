// The registry: backends by name, compiled in when their dependency was found.
#include <sstream>

#include "rtcd/error.hpp"
#include "rtcd/narrow_phase.hpp"
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
CpuFallback opencl_fallback(const std::string& name) {
  if (name.rfind("opencl-basic", 0) == 0) return {"basic", make_basic_tracers};
#ifdef RTCD_WITH_EMBREE
  return {"embree", [] { return make_embree_tracers(); }};
#else
  return {"basic", make_basic_tracers};
#endif
}
}  // namespace
#endif

std::unique_ptr<NarrowPhase> make_narrow_phase(const std::string& name, const Config& config) {
  config.validate();
  const auto list = available_backends();
  auto usable = [&](const std::string& n) {
    for (const auto& b : list)
      if (b.name == n) return b.usable;
    return false;
  };
  std::string chosen = name;
  // A fixed order, fastest first, so a run stays reproducible.
  if (name == "auto") chosen = usable("embree") ? "embree" : usable("opencl") ? "opencl" : "basic";
  if (chosen == "basic") return make_basic_narrow_phase(config);
#ifdef RTCD_WITH_OPENCL
  // Built even without a usable device: it says why and runs on the CPU.
  if (is_opencl_name(chosen)) return make_opencl_narrow_phase(chosen, config, opencl_fallback(chosen));
#endif
#ifdef RTCD_WITH_EMBREE
  if (is_embree_name(chosen) && usable("embree")) return make_embree_narrow_phase(chosen, config);
#endif
  std::ostringstream s;
  s << "backend '" << name << "' is not available; available:";
  for (const auto& b : list) s << ' ' << b.name << (b.usable ? "" : " (unusable: " + b.detail + ")");
  s << " auto";
  throw BackendError(s.str());
}

}  // namespace rtcd
