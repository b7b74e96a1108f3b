// Independent references from well-kept libraries, for the differential
// tests: FCL (mesh BVH collide and distance), Bullet's GIMPACT (mesh pairs
// through btGImpactCollisionAlgorithm) and libccd (GJK/EPA on convex
// shapes). Each is built once per shape, then queried at any pair of poses.
// Nothing here calls rtcd's kernel code: only the Shape/Mesh data is read.
#pragma once

#include <memory>
#include <vector>

#include <Eigen/Core>

#include "rtcd/geometry.hpp"
#include "rtcd/shape.hpp"

namespace rtcd::oracle {

// A contact point as a reference library reports it, in world frame.
struct ReferenceContact {
  Eigen::Vector3d position = Eigen::Vector3d::Zero();
  Eigen::Vector3d normal = Eigen::Vector3d::Zero();  // unit; the library's convention, from B towards A
  double depth = 0.0;                                // >= 0: penetration depth as the library reports it
};

struct ReferenceCollision {
  bool colliding = false;
  std::vector<ReferenceContact> contacts;  // empty when contacts were not asked for
};

// FCL 0.7: meshes as BVHModel<OBBRSS>, spheres and boxes as FCL primitives.
class FclShape {
 public:
  explicit FclShape(const Shape& shape);
  ~FclShape();
  FclShape(FclShape&&) noexcept;
  FclShape& operator=(FclShape&&) noexcept;

  // Boolean collide; with `contacts`, up to `max_contacts` contact points.
  ReferenceCollision collide(const Pose& pose, const FclShape& other, const Pose& other_pose, bool contacts = false,
                             size_t max_contacts = 1000) const;
  // Minimum distance between separated shapes (0 or below when they touch).
  double distance(const Pose& pose, const FclShape& other, const Pose& other_pose) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// Bullet's GIMPACT: meshes as btGImpactMeshShape, spheres and boxes as
// btSphereShape / btBoxShape, collided through the dispatcher that has the
// GImpact algorithm registered.
class GimpactShape {
 public:
  explicit GimpactShape(const Shape& shape);
  ~GimpactShape();
  GimpactShape(GimpactShape&&) noexcept;
  GimpactShape& operator=(GimpactShape&&) noexcept;

  // Contact points with depth > 0 (penetrating); colliding when any.
  ReferenceCollision collide(const Pose& pose, const GimpactShape& other, const Pose& other_pose) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// libccd on convex shapes: a sphere, a box, or a mesh taken as the convex
// hull of its vertices (the support function is the farthest vertex). A
// half-space has no support point: UsageError.
struct ConvexPenetration {
  bool colliding = false;
  double depth = 0.0;                                   // penetration depth (EPA); 0 when separated
  Eigen::Vector3d direction = Eigen::Vector3d::Zero();  // unit; move B by depth * direction to separate
  Eigen::Vector3d position = Eigen::Vector3d::Zero();
};

ConvexPenetration ccd_penetration(const Shape& a, const Pose& pose_a, const Shape& b, const Pose& pose_b);

}  // namespace rtcd::oracle
