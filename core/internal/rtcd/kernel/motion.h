/* Equation 2.1, the bound on how far a point of one body moved relative to
 * the other between two relative poses, and the relative pose it reads, by
 * one function that the host (the pipeline's decisions) and the devices
 * (rtcd_prepare, a pair's motion in its last step) both run, so both
 * derive the same limits from it. Plain arithmetic and a correctly rounded
 * sqrt only: OpenCL's atan2 may differ from the host's in its last bits, so
 * the angle's arctangent is computed here. */
#ifndef RTCD_KERNEL_MOTION_H
#define RTCD_KERNEL_MOTION_H

#include "frame.h"

#ifdef RTCD_HAS_DOUBLE
/* atan(y / x) for y, x >= 0, not both 0, in [0, pi / 2], within 8 ulp of
 * the library's (criterion_test): the ratio (at most 1, or its inverse
 * from pi / 2) is halved in angle by atan(r) = 2 atan(r / (1 + sqrt(1 +
 * r^2))) until it is at most 0.1 (three times at most; a resting pair's
 * never), where eleven terms of the odd series are exact to double
 * precision. */
RTCD_INLINE double rtcd_atan_ratio(double y, double x) {
  const int inverted = y > x;
  double r = inverted ? x / y : y / x, scale = 1.0, r2, sum;
  while (r > 0.1) {
    r = r / (1.0 + sqrt(1.0 + r * r));
    scale *= 2.0;
  }
  r2 = r * r;
  sum = 1.0 / 19.0 - r2 * (1.0 / 21.0);
  sum = 1.0 / 17.0 - r2 * sum;
  sum = 1.0 / 15.0 - r2 * sum;
  sum = 1.0 / 13.0 - r2 * sum;
  sum = 1.0 / 11.0 - r2 * sum;
  sum = 1.0 / 9.0 - r2 * sum;
  sum = 1.0 / 7.0 - r2 * sum;
  sum = 1.0 / 5.0 - r2 * sum;
  sum = 1.0 / 3.0 - r2 * sum;
  sum = 1.0 - r2 * sum;
  r = scale * (r * sum);
  return inverted ? 1.5707963267948966 - r : r;
}

/* The rotation angle in [0, pi] between unit quaternions q1 and q2 (w, x,
 * y, z); q and -q are the same rotation. Accurate near 0 and near pi. */
RTCD_INLINE double rtcd_rotation_angle(const double q1[4], const double q2[4]) {
  double d[4], s;
  rtcd_conjugate_product(q1, q2, d);
  s = sqrt(d[1] * d[1] + d[2] * d[2] + d[3] * d[3]);
  return s == 0.0 ? 0.0 : 2.0 * rtcd_atan_ratio(s, rtcd_abs_d(d[0]));
}

/* Equation 2.1: |t_a - t_b| + angle(q_a, q_b) * radius for relative poses a and b. */
RTCD_INLINE double rtcd_max_displacement(const rtcd_pose* a, const rtcd_pose* b, double radius) {
  const double dx = a->position[0] - b->position[0], dy = a->position[1] - b->position[1],
               dz = a->position[2] - b->position[2];
  return sqrt(dx * dx + dy * dy + dz * dz) + rtcd_rotation_angle(a->orientation, b->orientation) * radius;
}

/* A pair's relative pose, as equation 2.1 reads it: the lower id's frame in
 * the higher id's, unless the lower id's shape has no radius (a half-space:
 * a turn about its origin far away would read as a turn in place); then
 * the other way. */
RTCD_INLINE void rtcd_pair_relative(const rtcd_pose* low, const rtcd_pose* high, double low_radius, rtcd_pose* out) {
  if (low_radius > 0.0) {
    rtcd_relative_pose(low, high, out);
  } else {
    rtcd_relative_pose(high, low, out);
  }
}

/* A pair's motion between two steps' poses of its bodies (the lower id's,
 * then the higher id's), the m of the limits' rules: equation 2.1 with the
 * larger radius. */
RTCD_INLINE double rtcd_pair_motion(const rtcd_pose* low_before, const rtcd_pose* high_before,
                                    const rtcd_pose* low_now, const rtcd_pose* high_now, double low_radius,
                                    double high_radius) {
  rtcd_pose before, now;
  rtcd_pair_relative(low_before, high_before, low_radius, &before);
  rtcd_pair_relative(low_now, high_now, low_radius, &now);
  return rtcd_max_displacement(&before, &now, low_radius < high_radius ? high_radius : low_radius);
}

/* The motion of a pair of bodies a and b (either order) from the poses
 * `before` to `now`, both by body, their shapes' radii given. */
RTCD_INLINE double rtcd_bodies_motion(rtcd_uint a, rtcd_uint b, RTCD_GLOBAL const rtcd_pose* before,
                                      RTCD_GLOBAL const rtcd_pose* now, double radius_a, double radius_b) {
  const int a_low = a < b;
  const rtcd_uint low = a_low ? a : b, high = a_low ? b : a;
  const rtcd_pose low_before = before[low], high_before = before[high], low_now = now[low], high_now = now[high];
  return rtcd_pair_motion(&low_before, &high_before, &low_now, &high_now, a_low ? radius_a : radius_b,
                          a_low ? radius_b : radius_a);
}
#endif

#endif
