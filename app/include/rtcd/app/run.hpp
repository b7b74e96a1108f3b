// `rtcd run [SCENE]`: simulate a scene on Bullet with rtcd's narrow phase and
// leave steps.csv, summary.json, plots and snapshots in a run folder.
#pragma once

#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>

namespace rtcd::app {

struct RunOptions {
  std::string scene;  // empty: the default scene
  std::string backend;
  std::optional<uint64_t> steps;
  int threads = 0;  // 0: all
  std::string out;  // empty: runs/<scene>-<timestamp>/
  std::string record;  // not empty: the recording `rtcd replay` and `rtcd bench --replay` read
  // Also record the run (to `record`, else recording.rtcdrec in the run
  // folder) and write its page into view/ (rtcd view).
  bool view = false;
  bool no_plots = false;
  bool full_rays = false;  // snapshots draw whole rays, not the solver's segments
};

// Exit 0 done, 1 the simulation blew up (outputs so far kept), 2 bad input.
// `folder`, when given, receives the output folder.
int run_scene(const RunOptions& options, std::filesystem::path* folder = nullptr);

}  // namespace rtcd::app
