// Small geometric value types of the public API, poses and boxes, and the
// exact closest-point queries in double that oracles and mesh derivations share.
#pragma once

#include <Eigen/Geometry>

#include "rtcd/export.hpp"

namespace rtcd {
RTCD_PUBLIC_BEGIN

// A rigid placement: world = orientation * local + position. Double
// precision so bodies far from the origin keep their relative precision.
struct Pose {
  Eigen::Vector3d position = Eigen::Vector3d::Zero();
  Eigen::Quaterniond orientation = Eigen::Quaterniond::Identity();

  Eigen::Vector3d apply(const Eigen::Vector3d& local) const { return orientation * local + position; }
  Pose inverse() const {
    Eigen::Quaterniond inv = orientation.conjugate();
    return {inv * -position, inv};
  }
  // this ∘ other: first other, then this.
  Pose operator*(const Pose& other) const {
    return {orientation * other.position + position, orientation * other.orientation};
  }
};

// Throws UsageError when a component is not finite or the quaternion is far
// from unit length; returns the pose with its quaternion normalised.
Pose checked(const Pose& pose);

struct Aabb {
  Eigen::Vector3d min = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity());
  Eigen::Vector3d max = Eigen::Vector3d::Constant(-std::numeric_limits<double>::infinity());

  void extend(const Eigen::Vector3d& p) {
    min = min.cwiseMin(p);
    max = max.cwiseMax(p);
  }
  bool empty() const { return (min.array() > max.array()).any(); }
  bool contains(const Eigen::Vector3d& p) const {
    return (p.array() >= min.array()).all() && (p.array() <= max.array()).all();
  }
  Aabb grown(double margin) const {
    return {min.array() - margin, max.array() + margin};
  }
  Aabb intersection(const Aabb& other) const { return {min.cwiseMax(other.min), max.cwiseMin(other.max)}; }
  // The axis-aligned box around this box placed by `pose`.
  Aabb transformed(const Pose& pose) const;
  Aabb transformed(const Eigen::Matrix3d& rotation, const Eigen::Vector3d& translation) const;
};

// Closest point of triangle (a, b, c) to p, by the triangle's Voronoi
// regions (Ericson, Real-Time Collision Detection 5.1.5); a degenerate
// triangle answers a.
Eigen::Vector3d closest_on_triangle(const Eigen::Vector3d& p, const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                                    const Eigen::Vector3d& c);
// Closest distance between segments [p0, p1] and [q0, q1] (Ericson 5.1.9).
double segment_distance(const Eigen::Vector3d& p0, const Eigen::Vector3d& p1, const Eigen::Vector3d& q0,
                        const Eigen::Vector3d& q1);

RTCD_PUBLIC_END
}  // namespace rtcd
