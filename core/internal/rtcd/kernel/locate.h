/* Where a ray's line meets the plane of one triangle (section 2.1.2).
 * Watertight formulation: vertices are moved into a frame where the ray runs
 * along +z, and each edge function is the 2-D cross product of two projected
 * vertices. A vertex projects the same way in every triangle that holds it,
 * so the edge shared by two triangles gets exactly opposite values in each:
 * a line through a shared edge or vertex is never lost between triangles.
 * Decisions use only signs of products and sums (no division), so every
 * compiler that keeps IEEE rounding and does not contract agrees on them. */
#ifndef RTCD_KERNEL_LOCATE_H
#define RTCD_KERNEL_LOCATE_H

#include "types.h"

/* A ray with its shear precomputed once for all triangles it meets. */
typedef struct {
  rtcd_vec3 origin;
  rtcd_vec3 direction;
  int kx, ky, kz;
  float sx, sy, sz;
} rtcd_ray;

RTCD_INLINE rtcd_ray rtcd_make_ray(rtcd_vec3 origin, rtcd_vec3 direction) {
  rtcd_ray r;
  float ax = RTCD_FABS(direction.x), ay = RTCD_FABS(direction.y), az = RTCD_FABS(direction.z);
  r.origin = origin;
  r.direction = direction;
  r.kz = (ax > ay) ? (ax > az ? 0 : 2) : (ay > az ? 1 : 2);
  r.kx = (r.kz + 1) % 3;
  r.ky = (r.kx + 1) % 3;
  float dz = rtcd_component(direction, r.kz);
  if (dz < 0.0f) { /* keep the projected winding independent of the sign */
    int k = r.kx;
    r.kx = r.ky;
    r.ky = k;
  }
  r.sx = rtcd_component(direction, r.kx) / dz;
  r.sy = rtcd_component(direction, r.ky) / dz;
  r.sz = 1.0f / dz;
  return r;
}

/* Edge numbering of Algorithm 2 for a triangle (v0, v1, v2), with Möller's
 * barycentrics u (weight of v1) and v (weight of v2):
 *   edge 0 = (v2, v0), crossed when u < 0
 *   edge 1 = (v0, v1), crossed when v < 0
 *   edge 2 = (v1, v2), crossed when u + v > 1
 * The mesh's neighbour table uses the same numbering. */
typedef struct {
  int inside;   /* the line crosses the (closed) triangle */
  int edge;     /* when outside: the edge to cross, by the order of Algorithm 2 */
  int facing;   /* +1: the ray leaves through the triangle (direction . normal > 0); -1: enters; 0: edge-on */
  float t_num;  /* distance numerator: t = t_num / det, same sign as t */
  float det;    /* positive scale of the barycentrics, 0 when edge-on */
} rtcd_location;

RTCD_ALWAYS_INLINE rtcd_location rtcd_locate(const rtcd_ray* ray, rtcd_vec3 v0, rtcd_vec3 v1, rtcd_vec3 v2) {
  rtcd_location loc;
  rtcd_vec3 a = rtcd_sub(v0, ray->origin);
  rtcd_vec3 b = rtcd_sub(v1, ray->origin);
  rtcd_vec3 c = rtcd_sub(v2, ray->origin);
  float az = rtcd_component(a, ray->kz), bz = rtcd_component(b, ray->kz), cz = rtcd_component(c, ray->kz);
  float ax = rtcd_component(a, ray->kx) - ray->sx * az;
  float ay = rtcd_component(a, ray->ky) - ray->sy * az;
  float bx = rtcd_component(b, ray->kx) - ray->sx * bz;
  float by = rtcd_component(b, ray->ky) - ray->sy * bz;
  float cx = rtcd_component(c, ray->kx) - ray->sx * cz;
  float cy = rtcd_component(c, ray->ky) - ray->sy * cz;
  float w0 = cx * by - cy * bx; /* edge (v1, v2): weight of v0 */
  float w1 = ax * cy - ay * cx; /* edge (v2, v0): weight of v1 */
  float w2 = bx * ay - by * ax; /* edge (v0, v1): weight of v2 */
  float det = w0 + w1 + w2;
  float t_num = w0 * (ray->sz * az) + w1 * (ray->sz * bz) + w2 * (ray->sz * cz);
  loc.facing = det < 0.0f ? 1 : (det > 0.0f ? -1 : 0);
  if (det < 0.0f) {
    w0 = -w0;
    w1 = -w1;
    w2 = -w2;
    det = -det;
    t_num = -t_num;
  }
  loc.det = det;
  loc.t_num = t_num;
  loc.inside = 0;
  if (w1 < 0.0f) {
    loc.edge = 0;
  } else if (w2 < 0.0f) {
    loc.edge = 1;
  } else if (w0 < 0.0f) {
    loc.edge = 2;
  } else {
    loc.edge = -1;
    loc.inside = det > 0.0f;
  }
  return loc;
}

#endif
