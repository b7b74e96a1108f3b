// The exact reference: for one pair at given poses, which ray origins of one
// body lie inside the other, how far they are from its surface, and the
// first hit of each origin's inward ray, all in double precision by
// brute-force geometry over a plain bounding-volume tree. It reads the
// shapes' data and nothing of the kernel code it judges.
#pragma once

#include <memory>
#include <vector>

#include <Eigen/Core>

#include "rtcd/geometry.hpp"
#include "rtcd/shape.hpp"

namespace rtcd::oracle {

// What the reference knows of one ray origin against the target.
// Origins outside the target's bounds grown by the margin are outside and
// far; for the others every field is computed.
struct ExactRay {
  bool near = false;          // within the target's bounds grown by the margin
  bool inside = false;        // strictly inside the target (closed targets only)
  bool near_surface = false;  // closer to the target's surface than the margin
  double depth = -1.0;        // inside: first hit of the inward ray (t >= 0) on the target; -1 otherwise
  int32_t triangle = -1;      // the triangle (mesh) or face (box) hit first; -1 when none
  double penetration = -1.0;  // inside: distance to the target's nearest surface (the true depth); -1 otherwise
  bool deep() const { return inside && !near_surface; }
  bool far_outside() const { return !inside && !near_surface; }
};

// A shape in double precision, with a bounding-volume tree over its
// triangles when it is a mesh. Spheres and boxes are answered analytically.
class ExactShape {
 public:
  explicit ExactShape(std::shared_ptr<const Shape> shape);
  ~ExactShape();
  ExactShape(ExactShape&&) noexcept;
  ExactShape& operator=(ExactShape&&) noexcept;

  const Shape& shape() const { return *shape_; }
  // Inside/outside claims hold only for closed targets; an open mesh is
  // flagged here and callers leave it out of those claims.
  bool closed() const;

  // Queries in the shape's local frame.
  // Inside when the nearest surface crossing leaves the body, along three
  // fixed directions unrelated to the axes and to any ray of the method, the
  // majority deciding (a crossing exactly through an edge spoils at most one).
  bool inside(const Eigen::Vector3d& p) const;
  double distance(const Eigen::Vector3d& p) const;
  // The true penetration at p: its distance to the surface inside, 0 outside.
  double penetration(const Eigen::Vector3d& p) const { return inside(p) ? distance(p) : 0.0; }
  // The point of the surface nearest to p: inside, the true penetration's
  // way out (its distance is distance(p)).
  Eigen::Vector3d closest_point(const Eigen::Vector3d& p) const;
  // distance(p) < radius, found without searching the whole tree.
  bool within(const Eigen::Vector3d& p, double radius) const;
  // Nearest intersection of origin + t * direction, t >= 0, from either side.
  bool first_hit(const Eigen::Vector3d& origin, const Eigen::Vector3d& direction, double& t, int32_t& triangle) const;

  // Every ray origin of `source` (placed by source_pose) against this shape
  // (placed by pose); `margin` is the band around the surface where no
  // inside/outside claim is made.
  std::vector<ExactRay> rays_from(const Shape& source, const Pose& source_pose, const Pose& pose,
                                  double margin) const;

  // Every edge of `source` (RaySources::edges, placed by source_pose)
  // against this shape (placed by pose), for closed targets: -1 where an
  // end is inside or the edge does not cross the surface; otherwise the
  // greatest distance to the surface of the middles of the pieces of the
  // edge inside the target (every crossing of the segment with the surface
  // found, in order; a piece runs from an entering crossing to the next
  // leaving one). A depth beyond the margin is a crossing no vertex ray
  // sees. A half-space has none (an edge below its plane has an end below).
  std::vector<double> edge_depths(const Shape& source, const Pose& source_pose, const Pose& pose) const;
  // A sphere `source` against this sphere or box: how deep the sphere
  // reaches into it (the closed form); -1 when it does not, or for other
  // shapes.
  double sphere_depth(const Shape& source, const Pose& source_pose, const Pose& pose) const;

 private:
  struct Tree;
  std::shared_ptr<const Shape> shape_;
  std::unique_ptr<Tree> tree_;  // meshes only
};

// The one judgement of a contact against the true penetration at its point:
// it over-reports when its solver depth (the push's length) passes 1.25x
// the truth plus 1e-3 of the smaller body's radius.
inline bool over_reports(double solver_depth, double truth, double smaller_radius) {
  return solver_depth > 1.25 * truth + 1e-3 * smaller_radius;
}

}  // namespace rtcd::oracle
