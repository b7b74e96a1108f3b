// A simulation run recorded so that any narrow phase can be replayed on the
// very poses and broad-phase pairs it saw (`rtcd bench`): every body's shape
// pose and the pairs of every step, with what the step measured.
//
// File: "RTCDREC1", the scene file's path and text, then per step its
// measurements, the kinds of the bodies that appeared, every pose
// (float position, float quaternion: Bullet's own precision) and the pairs
// that left and joined the broad phase's set since the step before.
// Little-endian throughout.
#pragma once

#include <cstdint>
#include <fstream>
#include <string>
#include <string_view>
#include <vector>

#include "rtcd/error.hpp"
#include "rtcd/geometry.hpp"
#include "rtcd/results.hpp"
#include "rtcd/sim/scene.hpp"
#include "rtcd/sim/simulation.hpp"

namespace rtcd::sim {

// A file that is not a recording, or a truncated or inconsistent one; the
// message names the file, the step and what is wrong.
class RecordingError : public Error {
 public:
  using Error::Error;
};

// What a recorded step measured (from its StepRecord).
struct RecordedStep {
  uint64_t step = 0;
  double time = 0;
  uint32_t bodies = 0, pairs = 0, contacts = 0, ground_contacts = 0;
  double kinetic_energy = 0;
  double seconds_broad = 0, seconds_narrow = 0, seconds_solver = 0, seconds_effects = 0, seconds_total = 0;
};

// The state a replay sees at one step.
struct RecordedFrame {
  std::vector<Pose> poses;      // by BodyId
  std::vector<BodyPair> pairs;  // a < b, sorted
};

class Recording {
 public:
  // Throws RecordingError; the scene is read with `limits` (its mesh files
  // must still be where the scene says).
  static Recording read(const std::string& path, const SceneLimits& limits = {});
  static Recording parse(std::string_view bytes, const std::string& name, const SceneLimits& limits = {});

  const std::string& scene_path() const { return scene_path_; }
  const std::string& scene_text() const { return scene_text_; }
  const Scene& scene() const { return scene_; }
  // By BodyId: index into scene().bodies, or Simulation::kGroundKind.
  const std::vector<uint32_t>& kinds() const { return kinds_; }
  const std::vector<RecordedStep>& steps() const { return steps_; }

  // Walks the steps in order, rebuilding each one's poses and pairs.
  class Cursor {
   public:
    explicit Cursor(const Recording& r) : recording_(&r) {}
    // The next step's frame; false after the last.
    bool next(RecordedFrame& frame);
    uint64_t index() const { return next_ - 1; }  // of the frame last returned

   private:
    const Recording* recording_;
    uint64_t next_ = 0;
    std::vector<uint64_t> keys_, scratch_;
  };

 private:
  friend class Cursor;
  struct Encoded {
    std::vector<float> poses;  // 7 per body
    std::vector<uint64_t> left, joined;
  };
  std::string scene_path_, scene_text_;
  Scene scene_;
  std::vector<uint32_t> kinds_;
  std::vector<RecordedStep> steps_;
  std::vector<Encoded> encoded_;
};

// Appends a Simulation's steps to a recording file as they are run.
class RecordingWriter {
 public:
  // Throws RecordingError when the file cannot be written.
  RecordingWriter(const std::string& path, const std::string& scene_path, const std::string& scene_text);
  // Records the step `simulation` just ran.
  void append(const Simulation& simulation);
  void close();  // flushes; throws RecordingError on a write error

 private:
  std::string path_;
  std::ofstream out_;
  size_t kinds_written_ = 0;
  std::vector<uint64_t> keys_, previous_, left_, joined_;
  std::vector<Pose> poses_;
  std::vector<float> packed_;  // the step's poses as written
};

}  // namespace rtcd::sim
