// The families of shape pairs the differential tests, `rtcd validate` and
// the accuracy sweep draw from, and their random relative poses: from
// separated through grazing to deep, including one body wholly inside the
// other where the shapes allow it.
#pragma once

#include <cstdint>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include "rtcd/geometry.hpp"
#include "rtcd/shape.hpp"

namespace rtcd::validation {

struct Family {
  std::string name;
  std::string description;
  std::shared_ptr<const Shape> a, b;  // A is the smaller body
  bool convex = false;                // both convex: libccd applies
  double reach = 1.0;                 // centre distances are drawn from [0, reach]
  // Instead: A's centre lies off a point of B's surface along its normal
  // (a mesh), by up to twice A's radius either way, so a body far smaller
  // than the other meets its surface.
  bool at_surface = false;
  double thinnest = 1.0;              // thickness of the thinnest part of either body
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();  // pairs are placed around it

  // A displacement threshold small against both bodies: 1% of the larger
  // radius, and a tenth of the thinnest part. Motions this small between
  // full steps keep the walk's missed rays rare (the differential tests
  // bound them); at the default threshold a vertex entering sideways, with
  // no predictive ray, is missed more often (see docs/results).
  double iterative_threshold() const;
  // The motion per step of iterative validation runs (equation 2.1),
  // whatever the configuration under test: 0.5% of the larger radius, or
  // `motion` where the family sets one (a sheet, a body 1e4 times smaller
  // than the other: 0.5% of the larger would move them past themselves).
  double motion = 0.0;
  double step_motion() const;
};

// convex, concave, torus, plates, highres, primitives, bars (thin bars
// crossing), rings (a peg through a ring); the shapes real meshes have:
// knots (a thin tube), gears (teeth), coarse (tetrahedron, octahedron),
// boxes (12 triangles each), cacti (a branching body); the distance
// bound's hard cases: sheets (thinner than a grid cell, edges longer than
// one), tiny (bodies 1e-9 across, kMinBodySize), ratio (bodies 1e4 apart in
// size, kMaxSizeRatio: the small one at the large one's surface, or wholly
// inside it).
const std::vector<std::string>& family_names();
// Throws UsageError listing the names when `name` is not one of them.
Family make_family(const std::string& name);

struct PosePair {
  Pose a, b;
};

// The poses of pair `index` of a run with `seed`: each pair has its own
// generator, so any one pair can be replayed alone. Uniform random
// orientations; B's centre at a uniform distance in [0, reach] from A's
// along a uniform direction (at_surface: a point of B's surface, uniform by
// area, moved along its face's normal by up to twice A's radius, on A's centre);
// both placed around a random point near the family's origin.
PosePair random_poses(const Family& family, uint64_t seed, uint64_t index);

// The same pair after a small relative motion of B: equation 2.1 on it
// stays within `displacement` (for iterative-mode tests).
PosePair moved(const Family& family, const PosePair& poses, double displacement, uint64_t seed, uint64_t index);

}  // namespace rtcd::validation
