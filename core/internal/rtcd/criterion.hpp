// Equation 2.1: an upper bound on how far any point of a pair moved relative
// to the other since the pair's last full step.
#pragma once

#include "rtcd/geometry.hpp"

namespace rtcd {

// Rotation angle in [0, pi] between two orientations; q and -q are the same
// rotation. Accurate near 0 and near pi (atan2, not acos).
double rotation_angle(const Eigen::Quaterniond& q1, const Eigen::Quaterniond& q2);

// maxDis = |t_ni - t| + angle(q_ni, q) * max_radius, where (t, q) is the
// relative transform now and (t_ni, q_ni) at the last full step.
double max_displacement(const Pose& relative_at_full_step, const Pose& relative_now, double max_radius);

}  // namespace rtcd
