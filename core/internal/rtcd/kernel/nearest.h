/* Squared distance from a point to a triangle (closest point by the
 * triangle's Voronoi regions), for the full step's nearest-triangle query:
 * a vertex near the other surface is tracked even when neither of its rays
 * meets it, so a sideways entry is walked from there. */
#ifndef RTCD_KERNEL_NEAREST_H
#define RTCD_KERNEL_NEAREST_H

#include "types.h"

RTCD_INLINE rtcd_vec3 rtcd_add(rtcd_vec3 a, rtcd_vec3 b) { return rtcd_v3(a.x + b.x, a.y + b.y, a.z + b.z); }
RTCD_INLINE rtcd_vec3 rtcd_scale(rtcd_vec3 a, float s) { return rtcd_v3(a.x * s, a.y * s, a.z * s); }

RTCD_INLINE float rtcd_point_triangle_distance2(rtcd_vec3 p, rtcd_vec3 a, rtcd_vec3 b, rtcd_vec3 c) {
  rtcd_vec3 ab = rtcd_sub(b, a), ac = rtcd_sub(c, a), ap = rtcd_sub(p, a);
  float d1 = rtcd_dot(ab, ap), d2 = rtcd_dot(ac, ap);
  rtcd_vec3 q;
  if (d1 <= 0.0f && d2 <= 0.0f) {
    q = a;
  } else {
    rtcd_vec3 bp = rtcd_sub(p, b);
    float d3 = rtcd_dot(ab, bp), d4 = rtcd_dot(ac, bp);
    rtcd_vec3 cp = rtcd_sub(p, c);
    float d5 = rtcd_dot(ab, cp), d6 = rtcd_dot(ac, cp);
    float vc = d1 * d4 - d3 * d2, vb = d5 * d2 - d1 * d6, va = d3 * d6 - d5 * d4;
    if (d3 >= 0.0f && d4 <= d3) {
      q = b;
    } else if (d6 >= 0.0f && d5 <= d6) {
      q = c;
    } else if (vc <= 0.0f && d1 >= 0.0f && d3 <= 0.0f) {
      q = rtcd_add(a, rtcd_scale(ab, d1 / (d1 - d3)));
    } else if (vb <= 0.0f && d2 >= 0.0f && d6 <= 0.0f) {
      q = rtcd_add(a, rtcd_scale(ac, d2 / (d2 - d6)));
    } else if (va <= 0.0f && (d4 - d3) >= 0.0f && (d5 - d6) >= 0.0f) {
      q = rtcd_add(b, rtcd_scale(rtcd_sub(c, b), (d4 - d3) / ((d4 - d3) + (d5 - d6))));
    } else {
      float denom = 1.0f / (va + vb + vc);
      q = rtcd_add(a, rtcd_add(rtcd_scale(ab, vb * denom), rtcd_scale(ac, vc * denom)));
    }
  }
  rtcd_vec3 d = rtcd_sub(p, q);
  return rtcd_dot(d, d);
}

#endif
