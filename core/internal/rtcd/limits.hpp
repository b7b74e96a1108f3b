// The per-pair limits of a step — displacement threshold, distance extension,
// walk limit — derived from the scene when the Config leaves them unset (the
// thesis' constants "depend on the objects size and velocities"). Rules:
//
//   size s       the smaller bounding radius of the two shapes (a half-space
//                has none: the other's)
//   thickness f  the thinner shape's thickness (ShapeScale::thickness)
//   triangle e   the finer mesh's mean edge length
//   motion m     equation 2.1 between the pair's relative poses at the last
//                step and now (0 when either body was not in last step's pairs)
//
//   distance_extension     E = max(s / 10, min(2 m, s))  predictive rays see
//                          a step ahead at twice the current speed, up to
//                          the smaller body's size (a body moving farther
//                          in a step is past any ray); resting pairs still
//                          track a tenth of the smaller body
//   displacement_threshold T = min(E / 2, f / 4)  walks follow motions small
//                          against the thinnest part, where a concavity's gap
//                          or a thin wall can be jumped
//
// For bodies of unit radius at rest these are the thesis' constants (0.1,
// 0.05, 32); they scale with the bodies.
//   max_walk_steps         W = max(32, ceil(4 max(2 m, T) / e))   a walk
//                          crosses the distance it may have to cover four
//                          times over, in triangles; at most the larger
//                          mesh's triangle count (a longer walk is circling)
//
// A value set in the Config replaces its rule; the other two still keep
// T <= E (T = min(T, E) when E is set, E = max(E, T) when T is set).
#pragma once

#include <cstdint>
#include <limits>

#include "rtcd/config.hpp"
#include "rtcd/kernel/limits.h"
#include "rtcd/shape.hpp"

namespace rtcd {

// A pair's limits for one step. Always distance_extension >= displacement_threshold.
struct PairLimits {
  double displacement_threshold = 0.0;
  double distance_extension = 0.0;
  uint32_t max_walk_steps = 1;

  // How far from the target a vertex is watched. In automatic mode no point
  // moves farther than displacement_threshold relative to the target before
  // the pair is traced in full again; in iterative mode, the predictive reach.
  double watch_reach(Mode mode) const {
    return mode == Mode::automatic ? displacement_threshold : distance_extension;
  }
};

// What the rules read of one shape, measured once when it is registered.
struct ShapeScale {
  double radius = 0.0;  // Shape::radius(); 0 for a half-space
  // Meshes: the 10th percentile, over up to 256 vertices spread over the
  // vertex list, of the inward self-ray length — how far a vertex's inward
  // ray runs before it leaves the body. Sphere: the diameter; box: the
  // smallest extent; half-space: infinite.
  double thickness = std::numeric_limits<double>::infinity();
  double edge = std::numeric_limits<double>::infinity();  // meshes: mean edge length; volumes never walk
  uint32_t triangles = 0;                                  // meshes: triangle count
};

ShapeScale measure_scale(const Shape& shape);

// The rules' inputs as a device reads them.
rtcd_shape_scale to_kernel(const ShapeScale& scale);
rtcd_limit_settings limit_settings(const Config& config);

// The rules above (kernel/limits.h, rtcd_derive_limits); `motion` is m.
// The settings are limit_settings(config), made once by a caller that
// derives many.
PairLimits derive_limits(const rtcd_limit_settings& settings, const ShapeScale& a, const ShapeScale& b,
                         double motion);
inline PairLimits derive_limits(const Config& config, const ShapeScale& a, const ShapeScale& b, double motion) {
  return derive_limits(limit_settings(config), a, b, motion);
}

// Whether any limit is left to the rules (only then are scales and motions needed).
inline bool derives_limits(const Config& config) {
  return !config.displacement_threshold || !config.distance_extension || !config.max_walk_steps;
}

// The least extension the rules give a pair in which one shape has `radius`
// (hosts growing broad-phase boxes by half of it find every pair within it).
inline double resting_extension(double radius) { return rtcd_resting_extension(radius); }

}  // namespace rtcd
