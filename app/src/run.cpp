// `rtcd run`: the main job. Steps a scene, streams steps.csv, then writes
// summary.json, plots (Debian's python3-matplotlib) and snapshots.
#include "rtcd/app/run.hpp"

#include <sys/resource.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <ctime>
#include <algorithm>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <set>
#include <sstream>
#include <thread>

#include <nlohmann/json.hpp>
#include <tbb/task_arena.h>

#include "device_share.hpp"
#include "rtcd/app/console.hpp"
#include "rtcd/app/view.hpp"
#include "rtcd/clock.hpp"
#include "rtcd/knobs_json.hpp"
#include "rtcd/sim/recording.hpp"
#include "rtcd/sim/simulation.hpp"

namespace rtcd::app {
namespace {

namespace fs = std::filesystem;

std::string timestamp() {
  const std::time_t now = std::time(nullptr);
  std::tm tm{};
  localtime_r(&now, &tm);
  char text[32];
  std::strftime(text, sizeof text, "%Y%m%d-%H%M%S", &tm);
  return text;
}

double peak_rss_mib() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return double(u.ru_maxrss) / 1024.0;
}

constexpr const char* kCsvHeader =
    "step,time,bodies,seconds_broad,seconds_narrow,seconds_solver,seconds_effects,seconds_total,pairs,pairs_full,"
    "pairs_iterative,rays_full,rays_predictive,rays_iterative,contacts,predictive,solver_points,speculative_points,"
    "kinetic_energy,interpenetration,projected_interpenetration,deepest,true_penetration,deepest_true,deep_pairs,"
    "longest_deep_run,ground_depth_fraction";

void write_csv_row(std::ostream& out, const sim::StepRecord& r) {
  out << r.step << ',' << r.time << ',' << r.bodies << ',' << r.seconds_broad << ',' << r.seconds_narrow << ','
      << r.seconds_solver << ',' << r.seconds_effects << ',' << r.seconds_total << ',' << r.pairs << ',' << r.pairs_full
      << ',' << r.pairs_iterative << ',' << r.rays.rays_full << ',' << r.rays.rays_predictive << ','
      << r.rays.rays_iterative << ',' << r.contacts << ',' << r.predictive << ',' << r.solver_points << ','
      << r.speculative_points << ',' << r.kinetic_energy << ',';
  if (r.interpenetration >= 0)
    out << r.interpenetration << ',' << r.projected << ',' << r.deepest << ',' << r.true_penetration << ','
        << r.deepest_true << ',' << r.deep_pairs << ',' << r.longest_deep_run << ',' << r.ground_depth_fraction;
  else out << ",,,,,,,";
  out << '\n';
}

}  // namespace

int run_scene(const RunOptions& o, fs::path* folder) {
  const std::string scene_path = o.scene.empty() ? RTCD_DEFAULT_SCENE : o.scene;
  sim::Scene scene = sim::load_scene(scene_path);
  if (o.steps) {
    if (*o.steps < 1) throw UsageError("--steps must be at least 1");
    scene.steps = *o.steps;
    std::erase_if(scene.snapshot_steps, [&](int64_t k) { return k >= int64_t(scene.steps) || k < -int64_t(scene.steps); });
  }
  if (o.threads < 0) throw UsageError("--threads must be at least 1 (0: all cores)");
  // The narrow phase's own (BackendOptions::threads); Bullet steps on one.
  const size_t thread_count = o.threads > 0 ? size_t(o.threads) : size_t(tbb::this_task_arena::max_concurrency());

  const fs::path dir = o.out.empty() ? fs::path("runs") / (scene.name + "-" + timestamp()) : fs::path(o.out);
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (ec) throw UsageError("cannot create the output folder " + dir.string() + ": " + ec.message());
  if (folder) *folder = dir;
  std::ofstream csv(dir / "steps.csv");
  if (!csv) throw UsageError("cannot write " + (dir / "steps.csv").string());
  csv << std::setprecision(9) << kCsvHeader << '\n';

  sim::Simulation simulation(scene, o.backend, o.threads);
  std::optional<sim::RecordingWriter> recording;
  const std::string record = o.record.empty() && o.view ? (dir / "recording.rtcdrec").string() : o.record;
  if (!record.empty()) {
    std::ifstream in(scene_path);
    std::ostringstream text;
    text << in.rdbuf();
    recording.emplace(record, scene_path, text.str());
  }
  for (const std::string& w : simulation.warnings()) std::cerr << "rtcd: warning: " << w << '\n';
  std::cout << "scene " << scene.name << ": " << scene.body_count() << " bodies, " << scene.steps << " steps of "
            << scene.time_step << " s, backend " << simulation.backend() << ", narrow phase on " << thread_count << " threads\n";

  std::set<uint64_t> snapshot_at;
  if (scene.has(sim::Effect::snapshots))
    for (int64_t k : scene.snapshot_steps) snapshot_at.insert(k < 0 ? uint64_t(int64_t(scene.steps) + k) : uint64_t(k));
  std::vector<std::string> pictures;

  struct Totals {
    double broad = 0, narrow = 0, solver = 0, effects = 0, total = 0;
    double pairs = 0, rays = 0, contacts = 0;
  } totals;
  double rss_at_1000 = -1;
  DeviceShare devices;
  std::string failure;
  Progress progress(scene.steps);
  const auto start = Clock::now();
  try {
    for (uint64_t i = 0; i < scene.steps; ++i) {
      const sim::StepRecord& r = simulation.step();
      if (recording) recording->append(simulation);
      write_csv_row(csv, r);
      totals.broad += r.seconds_broad;
      totals.narrow += r.seconds_narrow;
      totals.solver += r.seconds_solver;
      totals.effects += r.seconds_effects;
      totals.total += r.seconds_total;
      totals.pairs += double(r.pairs);
      totals.rays += double(r.rays.rays());
      totals.contacts += double(r.contacts);
      devices.add(r.step, r.devices, r.cpu_fallback);
      if (snapshot_at.contains(i)) {
        const fs::path png = dir / ("snapshot_" + std::to_string(i) + ".png");
        sim::write_png(png.string(), simulation.snapshot(scene.snapshot_width, scene.snapshot_height, o.full_rays));
        pictures.push_back(png.string());
      }
      if (i + 1 == 1000) rss_at_1000 = peak_rss_mib();
      progress.update(i + 1);
    }
  } catch (const sim::SimulationError& e) {
    failure = e.what();
    std::cout << '\n';
  }
  csv.close();
  if (recording) recording->close();  // the steps run, up to a failure
  const double wall = seconds_since(start);
  const uint64_t done = simulation.steps_done();

  const sim::StepRecord& last = simulation.last();
  const sim::StageCounters& c = simulation.counters();
  nlohmann::json effects = nlohmann::json::array();
  for (sim::Effect e : scene.effects) effects.push_back(sim::to_string(e));
  nlohmann::json summary = {
      {"scene", {{"name", scene.name}, {"file", scene.path}, {"bodies", scene.body_count()}}},
      {"configuration",
       {{"backend", simulation.backend()},
        {"effects", effects},
        {"time_step", scene.time_step},
        {"steps", scene.steps},
        {"seed", scene.seed},
        {"sleeping", scene.sleeping},
        {"gravity", {scene.gravity.x(), scene.gravity.y(), scene.gravity.z()}},
        {"knobs", knobs_json(scene.narrow)},
        {"points_per_pair", scene.points_per_pair},
        {"solver_iterations", scene.solver_iterations},
        {"interpenetration_every", scene.interpenetration_every}}},
      {"backend", simulation.backend()},
      {"devices", simulation.devices()},
      {"device_rays", devices.rays},
      // The first step that fell back, and why; null: none did.
      {"cpu_fallback", devices.fallback_step ? nlohmann::json{{"step", *devices.fallback_step},
                                                               {"reason", devices.fallback_reason}}
                                             : nlohmann::json()},
      {"threads", thread_count},
      {"build_type", RTCD_BUILD_TYPE},
      {"machine", {{"cpu", machine()}, {"cores", std::thread::hardware_concurrency()}}},
      {"totals",
       {{"steps", done},
        {"wall_seconds", wall},
        {"seconds_broad", totals.broad},
        {"seconds_narrow", totals.narrow},
        {"seconds_solver", totals.solver},
        {"seconds_effects", totals.effects},
        {"mean_pairs", done ? totals.pairs / done : 0.0},
        {"mean_rays", done ? totals.rays / done : 0.0},
        {"mean_contacts", done ? totals.contacts / done : 0.0},
        {"final_bodies", last.bodies},
        {"final_kinetic_energy", last.kinetic_energy},
        {"state_hash", simulation.state_hash()},
        {"peak_rss_mib", peak_rss_mib()}}},
      {"stage_work",
       {{"gravity_forces", c.gravity_forces},
        {"narrow_phase_batches", c.narrow_phase_batches},
        {"friction_points", c.friction_points},
        {"restitution_points", c.restitution_points},
        {"speculative_points", c.speculative_points},
        {"interpenetration_passes", c.interpenetration_passes},
        {"snapshots", c.snapshots}}},
      {"snapshots", pictures},
  };
  if (std::ifstream file(scene.path); file) {
    try {
      summary["scene"]["definition"] = nlohmann::json::parse(file);  // the file as run
    } catch (const nlohmann::json::exception&) {
    }
  }
  if (rss_at_1000 >= 0) summary["totals"]["peak_rss_mib_at_1000_steps"] = rss_at_1000;
  if (last.interpenetration >= 0)
    summary["totals"]["final_interpenetration"] = {
        {"summed_depth", last.interpenetration},
        {"summed_projected_depth", last.projected},
        {"deepest", last.deepest},
        {"summed_true_penetration", last.true_penetration},
        {"deepest_true", last.deepest_true},
        {"deep_pairs", last.deep_pairs},
        {"longest_deep_run_steps", last.longest_deep_run},
        {"pairs", last.interpenetration_pairs}};
  if (last.longest_deep_run > 0) {
    const auto bodies = simulation.bodies();
    const auto label = [&](uint32_t k) { return k < bodies.size() ? bodies[k].label : std::string("ground"); };
    summary["totals"]["final_interpenetration"]["longest_deep_pair"] = {label(last.longest_deep_pair.a),
                                                                          label(last.longest_deep_pair.b)};
  }
  if (!failure.empty()) summary["error"] = failure;

  std::vector<std::string> plots;
  if (!o.no_plots && done > 0) {
    const std::string command = "/usr/bin/python3 '" + std::string(RTCD_PLOT_SCRIPT) + "' '" + dir.string() + "'";
    if (std::system(command.c_str()) != 0)
      std::cerr << "rtcd: warning: the plots were not made (" << command << " failed; python3-matplotlib installed?)\n";
    for (const char* name : {"time_per_step.png", "pairs_and_rays.png", "interpenetration.png"})
      if (fs::exists(dir / name)) plots.push_back((dir / name).string());
  }
  summary["plots"] = plots;
  if (o.view && done > 0) {
    const fs::path page = dir / "view";
    const size_t bytes = write_view_page(sim::Recording::read(record), page, true, "embree");
    summary["view"] = {{"index", (page / "index.html").string()}, {"bytes", bytes}};
  }
  std::ofstream(dir / "summary.json") << summary.dump(2) << '\n';

  const auto row = [&](const char* stage, double seconds) {
    std::printf("  %-14s %9.3f s  %8.2f ms/step  %5.1f%%\n", stage, seconds, done ? 1e3 * seconds / done : 0.0,
                totals.total > 0 ? 100 * seconds / totals.total : 0.0);
  };
  std::printf("%llu steps in %.2f s wall (%.1f steps/s); per stage:\n", (unsigned long long)done, wall,
              wall > 0 ? done / wall : 0.0);
  row("broad phase", totals.broad);
  row("narrow phase", totals.narrow);
  row("solver", totals.solver);
  row("other effects", totals.effects);
  row("step total", totals.total);
  std::printf("  mean pairs %.1f, rays %.0f, contacts %.1f per step; final kinetic energy %.4g J\n",
              done ? totals.pairs / done : 0.0, done ? totals.rays / done : 0.0, done ? totals.contacts / done : 0.0,
              last.kinetic_energy);
  if (last.interpenetration >= 0)
    std::printf("  interpenetration at the end: summed depth %.4g, summed projected depth %.4g, deepest %.4g over %zu "
                "pairs; true penetration summed %.4g, deepest %.4g\n",
                last.interpenetration, last.projected, last.deepest, last.interpenetration_pairs,
                last.true_penetration, last.deepest_true);
  std::printf("  output: %s\n", dir.string().c_str());
  if (!failure.empty()) {
    std::cerr << "rtcd: " << failure << " (outputs so far kept in " << dir.string() << ")\n";
    return 1;
  }
  return 0;
}

}  // namespace rtcd::app
