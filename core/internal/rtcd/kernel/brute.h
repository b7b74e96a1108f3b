/* The basic traversal: every triangle of a mesh, in id order, through
 * rtcd_locate; the tie rules of tracer.h. The CPU basic backend and the
 * device's brute-force tracer both run this. */
#ifndef RTCD_KERNEL_BRUTE_H
#define RTCD_KERNEL_BRUTE_H

#include "locate.h"
#include "nearest.h"
#include "tracer.h"

/* A hit with t_num >= 0 on a located triangle: the triangle's distance, else -1. */
RTCD_ALWAYS_INLINE float rtcd_hit_distance(const rtcd_ray* ray, rtcd_vec3 v0, rtcd_vec3 v1, rtcd_vec3 v2) {
  rtcd_location loc = rtcd_locate(ray, v0, v1, v2);
  if (!loc.inside || loc.t_num < 0.0f) return -1.0f;
  return loc.t_num / loc.det;
}

/* Nearest hit within [0, t_max] from either side; zero-area triangles are never hit. */
RTCD_INLINE rtcd_hit rtcd_brute_first_hit(const rtcd_ray* ray, RTCD_GLOBAL const rtcd_vec3* positions,
                                          RTCD_GLOBAL const rtcd_uint* triangles,
                                          RTCD_GLOBAL const rtcd_uchar* zero_area, rtcd_uint triangle_count,
                                          float t_max) {
  rtcd_hit best;
  rtcd_uint i;
  best.triangle = -1;
  best.t = t_max;
  for (i = 0; i < triangle_count; ++i) {
    float t;
    if (zero_area[i]) continue;
    t = rtcd_hit_distance(ray, positions[triangles[3 * i]], positions[triangles[3 * i + 1]],
                          positions[triangles[3 * i + 2]]);
    if (t >= 0.0f && t <= best.t && rtcd_hit_improves(best, t, (rtcd_int)i)) {
      best.t = t;
      best.triangle = (rtcd_int)i;
    }
  }
  return best;
}

/* The triangle nearest to `point` within `radius`, or -1. */
RTCD_INLINE rtcd_int rtcd_brute_nearest(rtcd_vec3 point, float radius, RTCD_GLOBAL const rtcd_vec3* positions,
                                        RTCD_GLOBAL const rtcd_uint* triangles,
                                        RTCD_GLOBAL const rtcd_uchar* zero_area, rtcd_uint triangle_count) {
  rtcd_int best = -1;
  float best_d2 = radius * radius;
  rtcd_uint i;
  for (i = 0; i < triangle_count; ++i) {
    float d2;
    if (zero_area[i]) continue;
    d2 = rtcd_point_triangle_distance2(point, positions[triangles[3 * i]], positions[triangles[3 * i + 1]],
                                       positions[triangles[3 * i + 2]]);
    if (d2 <= best_d2 && rtcd_nearer(best_d2, best, d2, (rtcd_int)i)) {
      best_d2 = d2;
      best = (rtcd_int)i;
    }
  }
  return best;
}

#endif
