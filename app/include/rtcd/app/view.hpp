// `rtcd view RECORDING --gltf FILE.glb`: a recorded run to watch in any
// glTF viewer or in Blender: one glTF 2.0 binary with each kind's mesh once
// (spheres and boxes tessellated, the ground a square under the bodies),
// one node per body, and each body's motion as one keyframe per recorded
// step.
#pragma once

#include <string>

namespace rtcd::app {

struct ViewOptions {
  std::string recording;  // recording.rtcdrec (rtcd run --record, rtcd bench)
  std::string gltf;       // the .glb to write
};

// Exit 0 written, 2 bad input (an unreadable recording, a path that cannot
// be written): then nothing is written.
int run_view(const ViewOptions& options);

}  // namespace rtcd::app
