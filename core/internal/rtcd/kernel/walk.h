/* The iterative ray/triangle-mesh intersection of Algorithm 1: from the
 * triangle a ray met last step, step across the edge Algorithm 2 names until
 * the triangle the line crosses is found, with an explicit ending status. */
#ifndef RTCD_KERNEL_WALK_H
#define RTCD_KERNEL_WALK_H

#include "locate.h"

typedef struct {
  int status;            /* an rtcd_line_status */
  rtcd_int triangle;     /* last triangle visited */
  float t;               /* distance along the ray when status is HIT or BEHIND */
  rtcd_uint steps;       /* triangles located */
} rtcd_walk_result;

/* Outcome of a located crossing: HIT/BEHIND on a triangle the ray leaves
 * through (direction . normal > 0), FRONT on one it enters. */
RTCD_INLINE int rtcd_crossing_status(int facing, float t_num) {
  if (facing <= 0) return RTCD_LINE_FRONT;
  return t_num >= 0.0f ? RTCD_LINE_HIT : RTCD_LINE_BEHIND;
}

/* positions: 3 floats per vertex; triangles: 3 vertex indices per triangle;
 * neighbors: 3 triangle indices per triangle in the edge numbering of
 * locate.h, -1 across a boundary edge; zero_area: 1 for a kept zero-area
 * triangle, which is never hit (the walk ends there as PARALLEL). */
RTCD_INLINE rtcd_walk_result rtcd_walk(const rtcd_ray* ray, RTCD_GLOBAL const rtcd_vec3* positions,
                                       RTCD_GLOBAL const rtcd_uint* triangles,
                                       RTCD_GLOBAL const rtcd_int* neighbors,
                                       RTCD_GLOBAL const rtcd_uchar* zero_area, rtcd_int start,
                                       rtcd_uint max_steps) {
  rtcd_walk_result r;
  rtcd_int previous = -1;
  rtcd_int tri = start;
  r.status = RTCD_LINE_STEP_LIMIT;
  r.triangle = start;
  r.t = 0.0f;
  r.steps = 0;
  while (r.steps < max_steps) {
    rtcd_location loc = rtcd_locate(ray, positions[triangles[3 * tri]], positions[triangles[3 * tri + 1]],
                                    positions[triangles[3 * tri + 2]]);
    r.steps += 1;
    r.triangle = tri;
    if (loc.det == 0.0f || zero_area[tri]) {
      r.status = RTCD_LINE_PARALLEL;
      return r;
    }
    if (loc.inside) {
      r.status = rtcd_crossing_status(loc.facing, loc.t_num);
      r.t = loc.t_num / loc.det;
      return r;
    }
    rtcd_int next = neighbors[3 * tri + loc.edge];
    if (next < 0) {
      r.status = RTCD_LINE_BOUNDARY;
      return r;
    }
    /* Edge functions of a shared edge are exact opposites, so between two
     * triangles facing the same way the walk never crosses back; turning
     * back means the surface folds over here and the line passes beside it. */
    if (next == previous) {
      r.status = RTCD_LINE_MISS;
      return r;
    }
    previous = tri;
    tri = next;
  }
  return r;
}

#endif
