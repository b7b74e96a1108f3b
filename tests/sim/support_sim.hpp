// Scenes written inline for the simulation tests.
#pragma once

#include <string>

#include "rtcd/sim/scene.hpp"

namespace rtcd::test {

// A scene from JSON text; mesh paths are resolved against data/scenes/.
inline sim::Scene scene_from(const std::string& json) {
  return sim::parse_scene(json, std::string(RTCD_DATA_DIR) + "/scenes/inline.json");
}

}  // namespace rtcd::test
