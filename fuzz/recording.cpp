// libFuzzer harness: recording files (`rtcd bench --replay`) through the
// reader, then every step rebuilt by the cursor. RecordingError is the
// accepted rejection; an accepted recording must give back, at every step,
// as many poses as it has bodies, all finite, and its pairs sorted, each of
// two distinct bodies it has, as many as the step says. The embedded scene's
// mesh files "exist" (nothing is loaded).
#include <cstdint>
#include <string>

#include "invariants.hpp"
#include "rtcd/sim/recording.hpp"

namespace {
using rtcd::fuzz::require;
}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  rtcd::sim::SceneLimits limits;
  limits.max_bodies = 64;
  limits.file_exists = [](const std::string&) { return true; };
  try {
    const auto recording =
        rtcd::sim::Recording::parse(std::string_view(reinterpret_cast<const char*>(data), size), "fuzz.rtcdrec", limits);
    rtcd::sim::Recording::Cursor cursor(recording);
    rtcd::sim::RecordedFrame frame;
    while (cursor.next(frame)) {
      const auto& step = recording.steps()[cursor.index()];
      require(frame.poses.size() == step.bodies, "pose count differs from the body count");
      require(frame.pairs.size() == step.pairs, "pair count differs from the step's");
      for (const auto& p : frame.poses)
        require(p.position.allFinite() && p.orientation.coeffs().allFinite(), "non-finite pose");
      for (size_t i = 0; i < frame.pairs.size(); ++i) {
        require(frame.pairs[i].a < frame.pairs[i].b && frame.pairs[i].b < step.bodies, "pair of bodies it lacks");
        require(i == 0 || std::pair(frame.pairs[i - 1].a, frame.pairs[i - 1].b) <
                              std::pair(frame.pairs[i].a, frame.pairs[i].b),
                "pairs out of order or repeated");
      }
    }
  } catch (const rtcd::sim::RecordingError&) {
  }
  return 0;
}
