// `rtcd view RECORDING|RUN_DIR`: a recorded run to watch.
// - A page (the default): a folder that opens by double-click from
//   file://: index.html, its script, Debian's three.js (r111, copied at
//   build time), and the run as data scripts: each kind's look once, every
//   body's pose per step, the recorded figures, and the contacts the narrow
//   phase finds when the recording is replayed through it.
// - `--gltf FILE.glb`: one glTF 2.0 binary (assimp's exporter) with each
//   kind's mesh once (spheres and boxes tessellated, the ground a square
//   under the bodies), one node per body and one keyframe per step.
#pragma once

#include <cstddef>
#include <filesystem>
#include <optional>
#include <string>

#include "rtcd/sim/recording.hpp"

namespace rtcd::app {

struct ViewOptions {
  std::string input;               // recording.rtcdrec, or a run folder holding one
  std::string out;                 // the page's folder; empty: view/ beside the recording
  std::string gltf;                // not empty: write this .glb (and a page only with `out` or `serve`)
  std::optional<int> serve;        // serve the page on 127.0.0.1:PORT once written, until stopped
  bool contacts = true;            // replay the recording for the contact overlay
  std::string backend = "embree";  // the replay's narrow phase
};

// Exit 0 written, 2 bad input (no recording, an unreadable one, a folder
// or file that cannot be written): then nothing is written or replaced.
int run_view(const ViewOptions& options);

// The recording `input` names: the file itself, or RUN_DIR/recording.rtcdrec.
// Throws UsageError naming what is missing.
std::string view_recording_path(const std::string& input);

// The page of `recording` into `folder`, replacing a page written there
// before (and nothing else); returns the folder's size in bytes.
size_t write_view_page(const sim::Recording& recording, const std::filesystem::path& folder, bool contacts,
                       const std::string& backend);

}  // namespace rtcd::app
