/* The fold check's shortcut: whether a segment from a walked contact's
 * origin to its face, inside the face's inner side, provably crosses no
 * other face, from what rtcd::Mesh::FoldGuard derived once per triangle.
 * Where it cannot tell, the caller casts a ray (trace.h). */
#ifndef RTCD_KERNEL_FOLD_H
#define RTCD_KERNEL_FOLD_H

#include "types.h"

/* What the check reads per triangle (rtcd::Mesh::FoldGuard::Face). */
typedef struct {
  float clearance; /* no other face reaching into the inner side comes closer */
  float offset;    /* n . v0 along the unit normal */
  float size;      /* |v0|_1 */
} rtcd_fold_face;

/* The segment runs from `origin` along the unit `toward` for `reach`, to a
 * point of triangle `face`. Faces beyond the face's ring are farther than
 * its clearance; each ring face is missed when both ends lie on one side of
 * its plane by more than the rounding of the test (relative 1e-5 of the
 * magnitudes involved: the origin, the reach and the plane's vertex). */
RTCD_INLINE int rtcd_fold_free(rtcd_int face, rtcd_vec3 origin, rtcd_vec3 toward, float reach,
                               RTCD_GLOBAL const rtcd_vec3* normals, RTCD_GLOBAL const rtcd_fold_face* faces,
                               RTCD_GLOBAL const rtcd_uint* ring_first, RTCD_GLOBAL const rtcd_int* ring) {
  rtcd_uint k;
  float base;
  if (!(reach * 1.001f < faces[face].clearance)) return 0;
  base = 1.0e-5f * (2.0f * (RTCD_FABS(origin.x) + RTCD_FABS(origin.y) + RTCD_FABS(origin.z)) + reach);
  for (k = ring_first[face]; k < ring_first[face + 1]; ++k) {
    rtcd_int g = ring[k];
    rtcd_vec3 n = normals[g];
    float start = rtcd_dot(n, origin) - faces[g].offset; /* the origin's side of g's plane */
    float end = start + reach * rtcd_dot(n, toward);      /* the face point's */
    float tolerance = base + 1.0e-5f * faces[g].size;
    if (!((start < -tolerance && end < -tolerance) || (start > tolerance && end > tolerance))) return 0;
  }
  return 1;
}

#endif
