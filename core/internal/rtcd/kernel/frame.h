/* A job's frame: the source-to-target transform and the candidate box, in
 * double, made from the two bodies' poses and the shapes' bounds by one
 * function that the host (the pipeline's place) and the devices (the
 * executor's rtcd_prepare) both run, so their frames are the same bits.
 * Plain arithmetic only (no sqrt, no fma: contraction is off). */
#ifndef RTCD_KERNEL_FRAME_H
#define RTCD_KERNEL_FRAME_H

#include "types.h"

#ifdef RTCD_HAS_DOUBLE
/* The source-to-target transform and the candidate box, in double. */
typedef struct {
  double rotation[9]; /* row-major */
  double translation[3];
  double lo[3]; /* candidate box in the target frame */
  double hi[3];
} rtcd_frame;

/* A body's pose: a unit quaternion (w, x, y, z), then the position. 56 bytes. */
typedef struct {
  double orientation[4];
  double position[3];
} rtcd_pose;

/* A shape's bounds in its own frame. */
typedef struct {
  double lo[3];
  double hi[3];
} rtcd_box;

/* The rotation of unit quaternion q, row-major (the formula of Eigen's toRotationMatrix). */
RTCD_INLINE void rtcd_quaternion_matrix(const double q[4], double r[9]) {
  double tx = 2.0 * q[1], ty = 2.0 * q[2], tz = 2.0 * q[3];
  double twx = tx * q[0], twy = ty * q[0], twz = tz * q[0];
  double txx = tx * q[1], txy = ty * q[1], txz = tz * q[1];
  double tyy = ty * q[2], tyz = tz * q[2], tzz = tz * q[3];
  r[0] = 1.0 - (tyy + tzz);
  r[1] = txy - twz;
  r[2] = txz + twy;
  r[3] = txy + twz;
  r[4] = 1.0 - (txx + tzz);
  r[5] = tyz - twx;
  r[6] = txz - twy;
  r[7] = tyz + twx;
  r[8] = 1.0 - (txx + tyy);
}

RTCD_INLINE double rtcd_abs_d(double x) { return x < 0.0 ? -x : x; }

/* conj(a) b for quaternions (w, x, y, z). */
RTCD_INLINE void rtcd_conjugate_product(const double a[4], const double b[4], double q[4]) {
  q[0] = a[0] * b[0] + a[1] * b[1] + a[2] * b[2] + a[3] * b[3];
  q[1] = a[0] * b[1] - a[1] * b[0] - a[2] * b[3] + a[3] * b[2];
  q[2] = a[0] * b[2] - a[2] * b[0] - a[3] * b[1] + a[1] * b[3];
  q[3] = a[0] * b[3] - a[3] * b[0] - a[1] * b[2] + a[2] * b[1];
}

/* The source body's pose in the target body's frame: orientation
 * conj(q_target) q_source, position R_target^T (p_source - p_target). */
RTCD_INLINE void rtcd_relative_pose(const rtcd_pose* source, const rtcd_pose* target, rtcd_pose* out) {
  double rt[9], d[3];
  int i;
  rtcd_conjugate_product(target->orientation, source->orientation, out->orientation);
  rtcd_quaternion_matrix(target->orientation, rt);
  for (i = 0; i < 3; ++i) d[i] = source->position[i] - target->position[i];
  for (i = 0; i < 3; ++i) out->position[i] = rt[i] * d[0] + rt[3 + i] * d[1] + rt[6 + i] * d[2];
}

/* The frame of the source body in the target body's (rtcd_relative_pose);
 * the candidate box is the source's bounds placed there (centre and
 * half-extents through |R|), cut to the target's bounds and grown by
 * `extension`. */
RTCD_INLINE void rtcd_relative_frame(const rtcd_pose* source, const rtcd_pose* target, const rtcd_box* source_bounds,
                                     const rtcd_box* target_bounds, double extension, rtcd_frame* f) {
  rtcd_pose relative;
  double centre[3], extent[3], c, h;
  int i;
  rtcd_relative_pose(source, target, &relative);
  rtcd_quaternion_matrix(relative.orientation, f->rotation);
  for (i = 0; i < 3; ++i) {
    f->translation[i] = relative.position[i];
    centre[i] = 0.5 * (source_bounds->lo[i] + source_bounds->hi[i]);
    extent[i] = 0.5 * (source_bounds->hi[i] - source_bounds->lo[i]);
  }
  for (i = 0; i < 3; ++i) {
    const double* row = f->rotation + 3 * i;
    c = row[0] * centre[0] + row[1] * centre[1] + row[2] * centre[2] + f->translation[i];
    h = rtcd_abs_d(row[0]) * extent[0] + rtcd_abs_d(row[1]) * extent[1] + rtcd_abs_d(row[2]) * extent[2];
    f->lo[i] = (c - h > target_bounds->lo[i] ? c - h : target_bounds->lo[i]) - extension;
    f->hi[i] = (c + h < target_bounds->hi[i] ? c + h : target_bounds->hi[i]) + extension;
  }
}
#endif

#endif
