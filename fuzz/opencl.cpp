// libFuzzer harness for the OpenCL backend: the mesh_pair input
// (pair_input.hpp) stepped on `opencl-basic` and on the CPU's `basic`; every
// step must satisfy invariants.hpp and be the same bit for bit (contacts,
// predictive rays, pair summaries, statistics), in every mode. The OpenCL
// context and its built program live for the whole run (the backend keeps
// one per device set), so an input costs a narrow phase, not a driver
// start. PoCL's CPU devices serve (scripts/fuzz.sh sets POCL_DEVICES).
#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <cstring>

#include "rtcd/backend.hpp"

#include <tbb/global_control.h>

#include "invariants.hpp"
#include "pair_input.hpp"

namespace {

using namespace rtcd;

tbb::global_control one_thread(tbb::global_control::max_allowed_parallelism, 1);

// Aborts (a finding) when the run has no usable OpenCL device: fuzzing the
// fallback alone would prove nothing.
const bool have_opencl = [] {
  for (const auto& b : available_backends())
    if (b.name == "opencl-basic" && b.usable) return true;
  std::fprintf(stderr, "fuzz_opencl: no usable OpenCL device (install pocl-opencl-icd)\n");
  std::abort();
}();

bool same(const RayRecord& x, const RayRecord& y) {
  return x.source == y.source && x.source_body == y.source_body && x.target_body == y.target_body &&
         x.vertex == y.vertex && x.triangle == y.triangle && x.origin == y.origin && x.direction == y.direction &&
         x.normal == y.normal;
}

// Bit-for-bit equality of two steps, but the clock readings.
void require_same(const StepResult& x, const StepResult& y, const std::string& where) {
  fuzz::require(x.pairs.size() == y.pairs.size() && x.contacts.size() == y.contacts.size() &&
                    x.predictive.size() == y.predictive.size(),
                where + ": different counts (" + std::to_string(x.contacts.size()) + " and " +
                    std::to_string(y.contacts.size()) + " contacts)");
  for (size_t i = 0; i < x.pairs.size(); ++i)
    fuzz::require(x.pairs[i].colliding == y.pairs[i].colliding && x.pairs[i].mode == y.pairs[i].mode &&
                      x.pairs[i].max_depth == y.pairs[i].max_depth,
                  where + ": different pair summaries");
  for (size_t k = 0; k < x.contacts.size(); ++k) {
    const Contact &a = x.contacts[k], &b = y.contacts[k];
    fuzz::require(same(a, b) && a.kind == b.kind && a.edge == b.edge && a.depth == b.depth &&
                      a.projected_depth == b.projected_depth && a.push == b.push,
                  where + ": contact " + std::to_string(k) + " differs (vertex " + std::to_string(a.vertex) + ", " +
                      std::to_string(b.vertex) + ")");
  }
  for (size_t k = 0; k < x.predictive.size(); ++k)
    fuzz::require(same(x.predictive[k], y.predictive[k]) && x.predictive[k].distance == y.predictive[k].distance,
                  where + ": predictive ray " + std::to_string(k) + " differs");
  const StepStats &a = x.stats, &b = y.stats;
  fuzz::require(a.candidates == b.candidates && a.rays_full == b.rays_full && a.rays_predictive == b.rays_predictive &&
                    a.rays_iterative == b.rays_iterative && a.walk_steps == b.walk_steps &&
                    a.nearest_queries == b.nearest_queries && a.rays_retraced == b.rays_retraced &&
                    a.rays_watched == b.rays_watched && a.walk_endings == b.walk_endings &&
                    a.edges_tested == b.edges_tested && a.edge_rays == b.edge_rays && a.edge_contacts == b.edge_contacts,
                where + ": different statistics");
}

// The device ran the step, not the CPU fallback (whose answers equal
// `basic` by design): no fallback, every candidate ray on a device, and each
// pair's two directions on one device, its own (PairResult::device), the
// one it first ran on (`first_devices`, filled at the first step).
void require_on_devices(const StepResult& step, std::vector<int32_t>& first_devices, const std::string& where) {
  const StepStats& s = step.stats;
  fuzz::require(s.cpu_fallback.empty(), where + ": fell back to the CPU: " + s.cpu_fallback);
  fuzz::require(!s.devices.empty(), where + ": no device work reported");
  size_t rays = 0, busy = 0;
  for (const DeviceWork& d : s.devices) {
    rays += d.rays;
    busy += d.jobs > 0;
  }
  const size_t items = s.candidates + s.edges_tested;
  fuzz::require(rays == items, where + ": " + std::to_string(items - rays) + " rays and edges not run on a device");
  fuzz::require(busy <= step.pairs.size(), where + ": a pair's directions on two devices");
  if (first_devices.empty())
    for (const PairResult& p : step.pairs) first_devices.push_back(p.device);
  for (size_t i = 0; i < step.pairs.size(); ++i) {
    const int32_t d = step.pairs[i].device;
    if (step.pairs[i].mode == PairMode::certified) continue;
    fuzz::require(d >= 0 && size_t(d) < s.devices.size(), where + ": a pair on no device");
    fuzz::require(d == first_devices[i], where + ": a pair moved from device " + std::to_string(first_devices[i]) +
                                             " to " + std::to_string(d));
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t length) {
  const auto input = fuzz::read_pair_case(data, length);
  if (!input) return 0;
  const std::vector<StepResult> device = fuzz::run_pair_case(*input, "opencl-basic");
  const std::vector<StepResult> cpu = fuzz::run_pair_case(*input, "basic");
  std::vector<int32_t> first_devices;
  for (int s = 0; s < input->steps; ++s) {
    require_on_devices(device[s], first_devices, "step " + std::to_string(s));
    require_same(device[s], cpu[s], "step " + std::to_string(s));
  }
  return 0;
}
