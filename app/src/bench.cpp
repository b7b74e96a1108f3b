// `rtcd bench`: runs the experiments, then draws the plots
// (scripts/plot_bench.py with Debian's python3-matplotlib).
#include "rtcd/app/bench.hpp"

#include <filesystem>
#include <iostream>
#include <memory>
#include <thread>

#include "rtcd/app/console.hpp"
#include "rtcd/error.hpp"
#include "rtcd/experiments/bench.hpp"

namespace rtcd::app {
namespace {
namespace fs = std::filesystem;

// "avalanche" names data/scenes/avalanche.json; anything else is a path.
std::string scene_file(const std::string& name) {
  if (fs::exists(name)) return name;
  const fs::path named = fs::path(RTCD_SCENES_DIR) / (name + ".json");
  if (name.find('/') == std::string::npos && fs::exists(named)) return named.string();
  throw UsageError(name + ": no such scene file, nor a scene of that name in " + std::string(RTCD_SCENES_DIR));
}

}  // namespace

int run_bench(experiments::BenchOptions b, bool plots) {
  if (b.replay.empty() == b.scene.empty()) throw UsageError("give a SCENE, or --replay FILE (not both)");
  if (!b.scene.empty()) b.scene = scene_file(b.scene);
  const std::string name = fs::path(b.scene.empty() ? b.replay : b.scene).stem().string();
  if (b.out.empty()) b.out = (fs::path("runs") / ("bench-" + name)).string();
  b.command = "Machine: " + machine() + ", " + std::to_string(std::thread::hardware_concurrency()) +
              " cores; build " RTCD_BUILD_TYPE "; command `" + b.command + "`.";
  std::unique_ptr<Progress> bar;
  std::string stage;
  b.progress = [&](const std::string& s, uint64_t done, uint64_t total) {
    if (s != stage || !bar) {
      stage = s;
      bar = std::make_unique<Progress>(total, s);
    }
    bar->update(done);
  };
  const std::string report = experiments::run_bench(b);
  if (plots) {
    const std::string command = "/usr/bin/python3 '" + std::string(RTCD_BENCH_PLOT_SCRIPT) + "' '" + b.out + "'";
    if (std::system(command.c_str()) != 0)
      std::cerr << "rtcd: warning: the plots were not made (" << command << " failed; python3-matplotlib installed?)\n";
  }
  std::cout << b.command << "\nreport: " << report << '\n';
  return 0;
}

}  // namespace rtcd::app
