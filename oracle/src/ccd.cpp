// libccd reference for convex pairs: GJK + EPA penetration depth between
// spheres, boxes and meshes taken as the convex hull of their vertices, all
// through world-frame support functions built from the poses.
#include <ccd/ccd.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <type_traits>
#include <variant>

#include <Eigen/Geometry>

#include "rtcd/error.hpp"
#include "rtcd/oracle/third_party.hpp"

namespace rtcd::oracle {

namespace {

// Debian builds libccd with CCD_DOUBLE; the conversions below rely on it.
static_assert(std::is_same_v<ccd_real_t, double>, "libccd must be built in double precision");

// A shape placed in the world, as libccd's support callbacks see it.
struct Placed {
  const Shape* shape;
  Eigen::Matrix3d rotation;
  Eigen::Vector3d position;
  Eigen::Vector3d first_dir = Eigen::Vector3d::UnitX();  // GJK's start, read from A only
};

Eigen::Vector3d local_support(const Shape& shape, const Eigen::Vector3d& d) {
  if (const Sphere* s = std::get_if<Sphere>(&shape.geometry())) {
    const double n = d.norm();
    return n > 0.0 ? Eigen::Vector3d(d * (s->radius / n)) : Eigen::Vector3d(s->radius, 0.0, 0.0);
  }
  if (const Box* b = std::get_if<Box>(&shape.geometry())) {
    const Eigen::Vector3d& h = b->half_extents;
    return {d.x() >= 0.0 ? h.x() : -h.x(), d.y() >= 0.0 ? h.y() : -h.y(), d.z() >= 0.0 ? h.z() : -h.z()};
  }
  // Mesh: the farthest vertex; a linear scan is enough for a reference.
  const auto positions = shape.mesh()->positions();
  Eigen::Vector3d best = positions.front().cast<double>();
  double best_dot = best.dot(d);
  for (const Eigen::Vector3f& p : positions) {
    const Eigen::Vector3d v = p.cast<double>();
    const double dot = v.dot(d);
    if (dot > best_dot) {
      best_dot = dot;
      best = v;
    }
  }
  return best;
}

Eigen::Vector3d world_support(const Placed& placed, const Eigen::Vector3d& d) {
  return placed.rotation * local_support(*placed.shape, placed.rotation.transpose() * d) + placed.position;
}

void support(const void* object, const ccd_vec3_t* dir, ccd_vec3_t* out) {
  const Eigen::Vector3d w = world_support(*static_cast<const Placed*>(object), {dir->v[0], dir->v[1], dir->v[2]});
  ccdVec3Set(out, w.x(), w.y(), w.z());
}

void center(const void* object, ccd_vec3_t* out) {
  const Placed& placed = *static_cast<const Placed*>(object);
  const Aabb& bounds = placed.shape->bounds();
  const Eigen::Vector3d c = placed.rotation * (0.5 * (bounds.min + bounds.max)) + placed.position;
  ccdVec3Set(out, c.x(), c.y(), c.z());
}

Placed place(const Shape& shape, const Pose& pose) {
  return {&shape, pose.orientation.normalized().toRotationMatrix(), pose.position};
}

// Support value of the Minkowski difference A - B along unit u: moving B by
// that much along u separates the pair, so it bounds the depth from above,
// and it equals the depth exactly along the true separating direction.
double difference_support(const Placed& a, const Placed& b, const Eigen::Vector3d& u) {
  return world_support(a, u).dot(u) - world_support(b, -u).dot(u);
}

// Where GJK starts on the retries below instead of libccd's default +x: a
// handful of generic directions, none along an axis.
constexpr double retry_dirs[][3] = {{-0.71, 0.23, 0.37}, {0.123, -0.977, 0.31}, {0.9, 0.1, -0.4}};

void first_dir(const void* a, const void*, ccd_vec3_t* dir) {
  const Eigen::Vector3d& d = static_cast<const Placed*>(a)->first_dir;
  ccdVec3Set(dir, d.x(), d.y(), d.z());
}

}  // namespace

// Debian's libccd 2.1 EPA is not reliable on its own, so its answers are
// checked (see `consider` below) and retried:
// - Whenever a support point lands in the plane of a polytope face (mixed tie
//   breaking, e.g. a mesh cube against a Box overlapping by 0.1 along x) or
//   now and then on spheres, it returns a depth near 0, or a partly converged
//   one, along a direction that does not separate the pair. Measured: up to 1
//   in 100 random box pairs, 1 in 12 sphere pairs. The check catches these,
//   and a retry from another start, or MPR's direction, gives the answer.
// - Its polytope expansion only splits the nearest face, so the polytope can
//   turn non-convex and stop on a face that is not the nearest one: the depth
//   then passes the check but is too deep. Seen only on deep pairs (depth
//   over half the summed radii; about 1 in 300 random pairs, up to 15% too
//   deep), never on shallower ones; not caught. FCL carries a patched copy of
//   libccd for both reasons.
// The returned depth is always the support of A - B along the direction, or
// EPA's own value where the two agree: moving B by it separates the pair.
ConvexPenetration ccd_penetration(const Shape& a, const Pose& pose_a, const Shape& b, const Pose& pose_b) {
  if (std::holds_alternative<HalfSpace>(a.geometry()) || std::holds_alternative<HalfSpace>(b.geometry()))
    throw UsageError("libccd needs bounded shapes: a half-space has no support point");
  Placed placed_a = place(a, pose_a);
  const Placed placed_b = place(b, pose_b);
  // EPA on a polytope pair is exact up to rounding; on a sphere it stops
  // within about 1e-6 (epa_tolerance below), and its direction is then a
  // little off, which the support along it magnifies: hence 1e-5 of the size.
  const double tolerance = 1e-5 * std::max(1e-3, a.radius() + b.radius());

  ccd_t ccd;
  CCD_INIT(&ccd);
  ccd.support1 = support;
  ccd.support2 = support;
  ccd.center1 = center;
  ccd.center2 = center;
  ccd.max_iterations = 1000;
  // libccd compares squared distances with this: 1e-12 stops EPA within
  // about 1e-6 on curved (sphere) pairs, where EPA converges slowly (each
  // run there costs 0.1 to 0.5 ms); polytopes converge exactly anyway.
  ccd.epa_tolerance = 1e-12;

  // Each EPA answer is judged by the support of A - B along its direction:
  // a correct answer has depth == that support, and the support is an upper
  // bound on the true depth either way. The answer with the least bound wins.
  ConvexPenetration out;
  double best_bound = std::numeric_limits<double>::infinity();
  bool verified = false;
  const auto consider = [&](ccd_real_t depth, const ccd_vec3_t& dir, const ccd_vec3_t& pos) {
    Eigen::Vector3d u(dir.v[0], dir.v[1], dir.v[2]);
    const double n = u.norm();
    if (!(n > 0.0) || !std::isfinite(n)) return;
    u /= n;
    const double bound = difference_support(placed_a, placed_b, u);
    const bool consistent = std::abs(bound - depth) <= tolerance;
    if (bound >= best_bound) return;
    best_bound = bound;
    verified = verified || consistent;
    out.depth = consistent ? double(depth) : bound;
    out.direction = u;
    out.position = Eigen::Vector3d(pos.v[0], pos.v[1], pos.v[2]);
  };

  // obj1 = A, obj2 = B. libccd documents `dir` as the direction to translate
  // obj2 by `depth` to reach touching contact, our convention as is (checked
  // by the cube and sphere tests: B on the +x side of A gives +x).
  ccd_real_t depth = 0.0;
  ccd_vec3_t dir;
  ccd_vec3_t pos;
  if (ccdGJKPenetration(&placed_a, &placed_b, &ccd, &depth, &dir, &pos) != 0) return out;
  out.colliding = true;
  consider(depth, dir, pos);

  // A failed check is retried from other GJK starts, which lead EPA
  // elsewhere; MPR's direction joins the candidates when none verifies.
  ccd.first_dir = first_dir;
  for (const auto& d : retry_dirs) {
    if (verified) break;
    placed_a.first_dir = Eigen::Vector3d(d[0], d[1], d[2]).normalized();
    if (ccdGJKPenetration(&placed_a, &placed_b, &ccd, &depth, &dir, &pos) == 0) consider(depth, dir, pos);
  }
  if (!verified && ccdMPRPenetration(&placed_a, &placed_b, &ccd, &depth, &dir, &pos) == 0) consider(depth, dir, pos);
  return out;
}

}  // namespace rtcd::oracle
