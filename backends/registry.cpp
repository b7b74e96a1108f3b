// The registry: backends by name, compiled in when their dependency was found.
#include <sstream>

#include "rtcd/error.hpp"
#include "rtcd/narrow_phase.hpp"
#include "basic/basic_backend.hpp"
#ifdef RTCD_WITH_EMBREE
#include "embree/embree_backend.hpp"
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
  return list;
}

std::unique_ptr<NarrowPhase> make_narrow_phase(const std::string& name, const Config& config) {
  config.validate();
  const auto list = available_backends();
  auto usable = [&](const std::string& n) {
    for (const auto& b : list)
      if (b.name == n) return b.usable;
    return false;
  };
  std::string chosen = name;
  if (name == "auto") chosen = usable("embree") ? "embree" : "basic";  // fastest first
  if (chosen == "basic") return make_basic_narrow_phase(config);
#ifdef RTCD_WITH_EMBREE
  if (chosen == "embree" && usable("embree")) return make_embree_narrow_phase(config);
#endif
  std::ostringstream s;
  s << "backend '" << name << "' is not available; available:";
  for (const auto& b : list) s << ' ' << b.name << (b.usable ? "" : " (unusable: " + b.detail + ")");
  s << " auto";
  throw BackendError(s.str());
}

}  // namespace rtcd
