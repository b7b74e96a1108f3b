// Equation 2.1: an upper bound on how far any point of a pair moved relative
// to the other since the pair's last full step.
#pragma once

#include "rtcd/geometry.hpp"
#include "rtcd/kernel/motion.h"

namespace rtcd {

// A pose as the kernel's functions take it (kernel/frame.h), and back: the same doubles.
inline rtcd_pose to_kernel(const Pose& pose) {
  const Eigen::Quaterniond& q = pose.orientation;
  return {{q.w(), q.x(), q.y(), q.z()}, {pose.position.x(), pose.position.y(), pose.position.z()}};
}
inline Pose from_kernel(const rtcd_pose& pose) {
  const double* q = pose.orientation;
  return {{pose.position[0], pose.position[1], pose.position[2]}, Eigen::Quaterniond(q[0], q[1], q[2], q[3])};
}

// Rotation angle in [0, pi] between two orientations; q and -q are the same
// rotation. Accurate near 0 and near pi (an arctangent, not acos).
double rotation_angle(const Eigen::Quaterniond& q1, const Eigen::Quaterniond& q2);

// maxDis = |t_ni - t| + angle(q_ni, q) * max_radius, where (t, q) is the
// relative transform now and (t_ni, q_ni) at the last full step
// (rtcd_max_displacement, the devices' function).
double max_displacement(const Pose& relative_at_full_step, const Pose& relative_now, double max_radius);

}  // namespace rtcd
