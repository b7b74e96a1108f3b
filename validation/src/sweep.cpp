// The accuracy sweep (see sweep.hpp).
#include "rtcd/validation/sweep.hpp"

#include <algorithm>
#include <functional>
#include <sstream>

namespace rtcd::validation {
namespace {

std::string text(double v) {
  std::ostringstream s;
  s << v;
  return s.str();
}

}  // namespace

std::vector<SweepPoint> sweep(const Family& family, const std::string& backend, size_t pairs, uint64_t seed,
                              const ShardRunner* runner) {
  struct Setting {
    std::string knob, value;
    RunMode mode;
    std::function<void(Config&)> apply;
  };
  std::vector<Setting> settings;
  settings.push_back({"mode", "full", RunMode::full, [](Config&) {}});
  settings.push_back({"mode", "iterative", RunMode::iterative, [](Config&) {}});
  for (uint32_t steps : {1u, 2u, 4u, 8u, 16u, 64u, 256u})
    settings.push_back({"max_walk_steps", std::to_string(steps), RunMode::iterative,
                        [steps](Config& c) { c.max_walk_steps = steps; }});
  for (double t : {0.005, 0.01, 0.02, 0.1})
    settings.push_back({"displacement_threshold", text(t), RunMode::iterative,
                        [t](Config& c) { c.displacement_threshold = t; }});  // the derived extension keeps >= t
  for (double e : {0.05, 0.2, 0.4})
    settings.push_back({"distance_extension", text(e), RunMode::iterative,
                        [e](Config& c) { c.distance_extension = e; }});
  settings.push_back({"predictive", "off", RunMode::iterative, [](Config& c) { c.predictive = false; }});
  settings.push_back({"verify_walks", "off", RunMode::iterative, [](Config& c) { c.verify_walks = false; }});
  settings.push_back({"edge_contacts", "off", RunMode::iterative, [](Config& c) { c.edge_contacts = false; }});
  settings.push_back({"edges_beside_contacts", "off", RunMode::iterative,
                      [](Config& c) { c.edges_beside_contacts = false; }});
  settings.push_back({"edges_both_sides", "off", RunMode::iterative,
                      [](Config& c) { c.edges_both_sides = false; }});
  for (double m : {0.005, 0.02})
    settings.push_back({"edge_retest_motion", text(m), RunMode::iterative,
                        [m](Config& c) { c.edge_retest_motion = m; }});

  std::vector<SweepPoint> points;
  for (const Setting& s : settings) {
    RunOptions o;
    o.backend = backend;
    o.mode = s.mode;
    o.pairs = pairs;
    o.seed = seed;
    o.with_oracles = false;
    s.apply(o.config);
    const auto run = runner ? run_family(family, o, *runner) : run_family(family, o);
    if (run) points.push_back({s.knob, s.value, s.knob == "mode" && s.value == "iterative", run->summary});
  }
  return points;
}

void write_csv(std::ostream& out, const std::vector<SweepPoint>& points) {
  out << "knob,value,default,family,backend,mode,pairs,seconds_per_pair,missed_rate,false_rays,mean_depth_error,"
         "max_relative_depth_error,missed_pair_rate,false_pairs\n";
  for (const SweepPoint& p : points) {
    const Summary& s = p.summary;
    out << p.knob << ',' << p.value << ',' << (p.is_default ? 1 : 0) << ',' << s.family << ',' << s.backend << ','
        << to_string(s.mode) << ',' << s.pairs << ',' << s.time_ours << ',' << s.missed_rate() << ',' << s.false_rays
        << ',' << s.mean_depth_error << ',' << s.max_relative_depth_error << ',' << s.missed_pair_rate() << ','
        << s.false_pairs << '\n';
  }
}

}  // namespace rtcd::validation
