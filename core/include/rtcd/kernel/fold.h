/* The fold check's shortcut: whether a segment from a walked contact's
 * origin to its face, inside the face's inner side, provably crosses no
 * other face, from what rtcd::Mesh::FoldGuard derived once per triangle.
 * Where it cannot tell, the caller casts a ray (trace.h). */
#ifndef RTCD_KERNEL_FOLD_H
#define RTCD_KERNEL_FOLD_H

#include "types.h"

/* The segment runs from `origin` along the unit `toward` for `reach`, to a
 * point of triangle `face`. Faces beyond the face's ring are farther than
 * its clearance; each ring face is missed when both ends lie on one side of
 * its plane by more than the rounding of the test (relative 1e-5 of the
 * distances involved). */
RTCD_INLINE int rtcd_fold_free(rtcd_int face, rtcd_vec3 origin, rtcd_vec3 toward, float reach,
                               RTCD_GLOBAL const rtcd_vec3* positions, RTCD_GLOBAL const rtcd_uint* triangles,
                               RTCD_GLOBAL const rtcd_vec3* normals, RTCD_GLOBAL const float* clearance,
                               RTCD_GLOBAL const rtcd_uint* ring_first, RTCD_GLOBAL const rtcd_int* ring) {
  rtcd_uint k;
  float magnitude;
  if (!(reach * 1.001f < clearance[face])) return 0;
  magnitude = RTCD_FABS(origin.x) + RTCD_FABS(origin.y) + RTCD_FABS(origin.z) + reach;
  for (k = ring_first[face]; k < ring_first[face + 1]; ++k) {
    rtcd_int g = ring[k];
    rtcd_vec3 n = normals[g];
    rtcd_vec3 d = rtcd_sub(origin, positions[triangles[3 * g]]);
    float start = rtcd_dot(n, d);                      /* the origin's side of g's plane */
    float end = start + reach * rtcd_dot(n, toward);   /* the face point's */
    float tolerance = 1.0e-5f * (magnitude + RTCD_FABS(d.x) + RTCD_FABS(d.y) + RTCD_FABS(d.z));
    if (!((start < -tolerance && end < -tolerance) || (start > tolerance && end > tolerance))) return 0;
  }
  return 1;
}

#endif
