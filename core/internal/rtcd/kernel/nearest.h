/* Squared distance from a point to a triangle (closest point by the
 * triangle's Voronoi regions), for the full step's nearest-triangle query:
 * a vertex near the other surface is tracked even when neither of its rays
 * meets it, so a sideways entry is walked from there. */
#ifndef RTCD_KERNEL_NEAREST_H
#define RTCD_KERNEL_NEAREST_H

#include "types.h"

RTCD_INLINE rtcd_vec3 rtcd_add(rtcd_vec3 a, rtcd_vec3 b) { return rtcd_v3(a.x + b.x, a.y + b.y, a.z + b.z); }
RTCD_INLINE rtcd_vec3 rtcd_scale(rtcd_vec3 a, float s) { return rtcd_v3(a.x * s, a.y * s, a.z * s); }

/* Worked relative to the triangle's first corner. The Voronoi tests
 * multiply four lengths, which would leave float's range at the sizes rtcd
 * supports (1e-9 to 1e12): a triangle outside 2^-20 .. 2^20 across is
 * scaled by the power of two nearest its size (exact), so they stay near
 * 1; the common sizes skip the scaling's two library calls. */
RTCD_ALWAYS_INLINE float rtcd_point_triangle_distance2(rtcd_vec3 p, rtcd_vec3 a, rtcd_vec3 b, rtcd_vec3 c) {
  rtcd_vec3 ab = rtcd_sub(b, a), ac = rtcd_sub(c, a), ap = rtcd_sub(p, a), bp, cp, q, d;
  float size = RTCD_FABS(ab.x), d1, d2, d3, d4, d5, d6, vc, vb, va, unit;
  int e;
  size = RTCD_FABS(ab.y) > size ? RTCD_FABS(ab.y) : size;
  size = RTCD_FABS(ab.z) > size ? RTCD_FABS(ab.z) : size;
  size = RTCD_FABS(ac.x) > size ? RTCD_FABS(ac.x) : size;
  size = RTCD_FABS(ac.y) > size ? RTCD_FABS(ac.y) : size;
  size = RTCD_FABS(ac.z) > size ? RTCD_FABS(ac.z) : size;
  e = size > 0.0f && (size < 9.5367431640625e-7f || size > 1048576.0f) ? RTCD_ILOGB(size) : 0;
  if (e != 0) {
    unit = RTCD_LDEXP(1.0f, -e);
    ab = rtcd_scale(ab, unit);
    ac = rtcd_scale(ac, unit);
    ap = rtcd_scale(ap, unit);
  }
  d1 = rtcd_dot(ab, ap);
  d2 = rtcd_dot(ac, ap);
  if (d1 <= 0.0f && d2 <= 0.0f) {
    q = rtcd_v3(0.0f, 0.0f, 0.0f);
  } else {
    bp = rtcd_sub(ap, ab);
    d3 = rtcd_dot(ab, bp);
    d4 = rtcd_dot(ac, bp);
    cp = rtcd_sub(ap, ac);
    d5 = rtcd_dot(ab, cp);
    d6 = rtcd_dot(ac, cp);
    vc = d1 * d4 - d3 * d2;
    vb = d5 * d2 - d1 * d6;
    va = d3 * d6 - d5 * d4;
    if (d3 >= 0.0f && d4 <= d3) {
      q = ab;
    } else if (d6 >= 0.0f && d5 <= d6) {
      q = ac;
    } else if (vc <= 0.0f && d1 >= 0.0f && d3 <= 0.0f) {
      q = rtcd_scale(ab, d1 / (d1 - d3));
    } else if (vb <= 0.0f && d2 >= 0.0f && d6 <= 0.0f) {
      q = rtcd_scale(ac, d2 / (d2 - d6));
    } else if (va <= 0.0f && (d4 - d3) >= 0.0f && (d5 - d6) >= 0.0f) {
      q = rtcd_add(ab, rtcd_scale(rtcd_sub(ac, ab), (d4 - d3) / ((d4 - d3) + (d5 - d6))));
    } else {
      float denom = 1.0f / (va + vb + vc);
      q = rtcd_add(rtcd_scale(ab, vb * denom), rtcd_scale(ac, vc * denom));
    }
  }
  d = rtcd_sub(ap, q);
  return e != 0 ? RTCD_LDEXP(rtcd_dot(d, d), 2 * e) : rtcd_dot(d, d);
}

#endif
