// JSON and table output of a query step.
#include "rtcd/app/report.hpp"

#include <cstdio>
#include <string>

namespace rtcd::app {
namespace {

nlohmann::json vec(const Eigen::Vector3d& v) { return {v.x(), v.y(), v.z()}; }

nlohmann::json record(const RayRecord& r) {
  return {{"source", r.source == Side::a ? "a" : "b"},
          {"vertex", r.vertex},
          {"triangle", r.triangle},
          {"origin", vec(r.origin)},
          {"direction", vec(r.direction)},
          {"normal", vec(r.normal)}};
}

}  // namespace

nlohmann::json stats_json(const StepStats& s) {
  nlohmann::json endings;
  for (int i = 0; i < kLineStatusCount; ++i) endings[line_status_name(i)] = s.walk_endings[i];
  nlohmann::json devices = nlohmann::json::array();
  for (const DeviceWork& d : s.devices)
    devices.push_back({{"jobs", d.jobs},
                       {"rays", d.rays},
                       {"launches", d.launches},
                       {"writes", d.writes},
                       {"reads", d.reads},
                       {"waits", d.waits},
                       {"bytes_to_device", d.bytes_to_device},
                       {"bytes_from_device", d.bytes_from_device},
                       {"bytes_recovery", d.bytes_recovery},
                       {"seconds_kernels", d.seconds_kernels},
                       {"seconds_copies", d.seconds_copies}});
  nlohmann::json j = {{"walk_endings", endings},
          {"devices", devices},
          {"cpu_fallback", s.cpu_fallback.empty() ? nlohmann::json() : nlohmann::json(s.cpu_fallback)},
          {"seconds", {{"prepare", s.seconds_prepare},
                       {"full", s.seconds_full},
                       {"iterative", s.seconds_iterative},
                       {"gather", s.seconds_gather},
                       {"device_kernels", s.seconds_device_kernels},
                       {"device_copies", s.seconds_device_copies}}}};
  for (const StepCounter& c : kStepCounters) j[c.name] = s.*c.field;
  for (const RayCounter& c : kRayCounters) j[c.name] = s.*c.field;
  return j;
}

nlohmann::json to_json(const StepResult& step) {
  const PairResult& pair = step.pairs.at(0);
  nlohmann::json contacts = nlohmann::json::array(), predictive = nlohmann::json::array();
  for (const Contact& c : step.contacts_of(pair)) {
    nlohmann::json j = record(c);
    j["kind"] = to_string(c.kind);
    if (c.kind == ContactKind::edge) j["edge"] = {c.edge[0], c.edge[1]};
    j["depth"] = c.depth;
    j["projected_depth"] = c.projected_depth;
    contacts.push_back(j);
  }
  for (const PredictiveRay& p : step.predictive_of(pair)) {
    nlohmann::json j = record(p);
    j["distance"] = p.distance;
    predictive.push_back(j);
  }
  return {{"colliding", pair.colliding},
          {"mode", to_string(pair.mode)},
          {"max_depth", pair.max_depth},
          {"device", pair.device},
          {"contacts", contacts},
          {"predictive", predictive},
          {"stats", stats_json(step.stats)}};
}

void print_table(std::ostream& out, const StepResult& step) {
  const PairResult& pair = step.pairs.at(0);
  char line[512];
  std::snprintf(line, sizeof line, "colliding: %s   mode: %s   contacts: %zu   max depth: %.6g   predictive: %zu\n",
                pair.colliding ? "yes" : "no", to_string(pair.mode), pair.contact_count, pair.max_depth,
                pair.predictive_count);
  out << line;
  // The source's vertex, or its edge as "v0-v1".
  auto row = [&](const RayRecord& r, const std::string& from, double value, const char* projected) {
    std::snprintf(line, sizeof line, "  %-3s %13s %8d %11.6g %11s  (%9.4f %9.4f %9.4f)  (%7.4f %7.4f %7.4f)\n",
                  r.source == Side::a ? "a" : "b", from.c_str(), r.triangle, value, projected, r.origin.x(),
                  r.origin.y(), r.origin.z(), r.normal.x(), r.normal.y(), r.normal.z());
    out << line;
  };
  char projected[32];
  if (pair.contact_count > 0) {
    out << "  src vertex or edge triangle       depth   projected  origin                           normal\n";
    for (const Contact& c : step.contacts_of(pair)) {
      std::snprintf(projected, sizeof projected, "%.6g", c.projected_depth);
      row(c,
          c.kind == ContactKind::edge ? std::to_string(c.edge[0]) + "-" + std::to_string(c.edge[1])
                                      : std::to_string(c.vertex),
          c.depth, projected);
    }
  }
  if (pair.predictive_count > 0) {
    out << "  predictive rays:\n  src vertex or edge triangle    distance           -  origin                           normal\n";
    for (const PredictiveRay& p : step.predictive_of(pair)) row(p, std::to_string(p.vertex), p.distance, "-");
  }
  const StepStats& s = step.stats;
  std::snprintf(line, sizeof line,
                "rays: %zu full, %zu predictive, %zu iterative (%zu traced again, %zu watched, %zu fold casts); "
                "candidates %zu; nearest queries %zu; walk steps %zu; edges %zu tested (%zu rays, %zu crossing); "
                "time %.3f ms\n",
                s.rays_full, s.rays_predictive, s.rays_iterative, s.rays_retraced, s.rays_watched, s.fold_casts,
                s.candidates, s.nearest_queries, s.walk_steps, s.edges_tested, s.edge_rays, s.edge_contacts,
                1e3 * (s.seconds_prepare + s.seconds_full + s.seconds_iterative + s.seconds_gather));
  out << line;
}

}  // namespace rtcd::app
