// The one interface every backend implements; rtcd/backend.hpp makes them.
#pragma once

#include <memory>
#include <span>
#include <string>
#include <vector>

#include "rtcd/config.hpp"
#include "rtcd/export.hpp"
#include "rtcd/geometry.hpp"
#include "rtcd/results.hpp"
#include "rtcd/shape.hpp"

namespace rtcd {
RTCD_PUBLIC_BEGIN

class NarrowPhase {
 public:
  virtual ~NarrowPhase() = default;

  // The backend's string form ("basic", "embree", "opencl:gpu", ...).
  virtual std::string name() const = 0;
  // Devices this instance runs on, in words.
  virtual std::vector<std::string> devices() const = 0;
  const Config& config() const { return config_; }

  // Registers a shape once (acceleration structures are built here, never
  // because a body moved). Many bodies may share one shape.
  virtual ShapeId add_shape(std::shared_ptr<const Shape> shape) = 0;
  virtual BodyId add_body(ShapeId shape, const Pose& pose) = 0;
  // Forgets the body and every pair state that involves it.
  virtual void remove_body(BodyId body) = 0;
  virtual void set_pose(BodyId body, const Pose& pose) = 0;

  // One step over the broad phase's candidate pairs. Pair state carries
  // from one call to the next; a pair absent from `pairs` is evicted.
  // `out` is overwritten; reusing it across steps keeps its buffers.
  virtual void detect(std::span<const BodyPair> pairs, StepResult& out) = 0;
  StepResult detect(std::span<const BodyPair> pairs) {
    StepResult out;
    detect(pairs, out);
    return out;
  }

  // detect in two halves, so a host works while the step runs (on the
  // narrow phase's own worker thread, started at the first call):
  // detect_begin checks the pairs (bad input throws here and loses nothing)
  // and starts the step; detect_done says whether it has finished, without
  // waiting; detect_end waits for it and throws what it threw. Until
  // detect_end returns, `pairs` and `out` are the step's, and every other
  // call on this narrow phase throws UsageError. A steady step allocates
  // nothing here either.
  virtual void detect_begin(std::span<const BodyPair> pairs, StepResult& out) = 0;
  virtual bool detect_done() const = 0;
  virtual void detect_end() = 0;

 protected:
  explicit NarrowPhase(Config config) : config_(config) { config_.validate(); }
  Config config_;
};

RTCD_PUBLIC_END
}  // namespace rtcd
