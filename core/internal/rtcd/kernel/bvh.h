/* Stackless traversal of a bounding-volume hierarchy flattened depth first:
 * a node's first child is the next node, and `escape` is the node after its
 * subtree, so traversal needs no stack (a device thread keeps no more than a
 * node index). The answers follow the tie rules of tracer.h whatever the
 * tree: boxes are pruned only when they cannot hold a hit as near as the
 * best one, with margins wider than the rounding of the box tests. */
#ifndef RTCD_KERNEL_BVH_H
#define RTCD_KERNEL_BVH_H

#include "brute.h"

typedef struct {
  rtcd_vec3 lo;
  rtcd_vec3 hi;
  rtcd_uint escape; /* the node after this subtree; the node count ends the traversal */
  rtcd_uint first;  /* leaves: first entry in the primitive list */
  rtcd_uint count;  /* leaves: number of triangles; 0: an inner node, its first child next */
} rtcd_bvh_node;

/* Relative margin on box distances: a few hundred float ulps, far more than
 * the box tests round. */
#define RTCD_BVH_MARGIN 1.0e-5f

/* Whether the ray's line can meet the box at some t in [0, t_max]: slabs
 * by division (correctly rounded), each end widened by the margin. */
RTCD_INLINE int rtcd_ray_meets_box(const rtcd_ray* ray, rtcd_vec3 lo, rtcd_vec3 hi, float t_max) {
  float t_near = 0.0f, t_far = t_max;
  int k;
  for (k = 0; k < 3; ++k) {
    float o = rtcd_component(ray->origin, k), d = rtcd_component(ray->direction, k);
    float l = rtcd_component(lo, k), h = rtcd_component(hi, k);
    float t0, t1, a, b;
    if (d == 0.0f) {
      if (o < l || o > h) return 0;
      continue;
    }
    t0 = (l - o) / d;
    t1 = (h - o) / d;
    a = t0 < t1 ? t0 : t1;
    b = t0 < t1 ? t1 : t0;
    a = a > 0.0f ? a * (1.0f - RTCD_BVH_MARGIN) : a * (1.0f + RTCD_BVH_MARGIN);
    b = b > 0.0f ? b * (1.0f + RTCD_BVH_MARGIN) : b * (1.0f - RTCD_BVH_MARGIN);
    if (a > t_near) t_near = a;
    if (b < t_far) t_far = b;
    if (t_near > t_far) return 0;
  }
  return 1;
}

/* Squared distance from a point to a box (0 inside). */
RTCD_INLINE float rtcd_box_distance2(rtcd_vec3 p, rtcd_vec3 lo, rtcd_vec3 hi) {
  float d2 = 0.0f;
  int k;
  for (k = 0; k < 3; ++k) {
    float c = rtcd_component(p, k), l = rtcd_component(lo, k), h = rtcd_component(hi, k);
    float d = c < l ? l - c : (c > h ? c - h : 0.0f);
    d2 += d * d;
  }
  return d2;
}

/* As rtcd_brute_first_hit, over the tree. */
RTCD_INLINE rtcd_hit rtcd_bvh_first_hit(const rtcd_ray* ray, RTCD_GLOBAL const rtcd_bvh_node* nodes,
                                        rtcd_uint node_count, RTCD_GLOBAL const rtcd_uint* primitives,
                                        RTCD_GLOBAL const rtcd_vec3* positions,
                                        RTCD_GLOBAL const rtcd_uint* triangles,
                                        RTCD_GLOBAL const rtcd_uchar* zero_area, float t_max) {
  rtcd_hit best;
  rtcd_uint n = 0;
  best.triangle = -1;
  best.t = t_max;
  while (n < node_count) {
    rtcd_bvh_node node = nodes[n];
    rtcd_uint k;
    if (!rtcd_ray_meets_box(ray, node.lo, node.hi, best.t)) {
      n = node.escape;
      continue;
    }
    if (node.count == 0) {
      n += 1;
      continue;
    }
    for (k = 0; k < node.count; ++k) {
      rtcd_uint i = primitives[node.first + k];
      float t;
      if (zero_area[i]) continue;
      t = rtcd_hit_distance(ray, positions[triangles[3 * i]], positions[triangles[3 * i + 1]],
                            positions[triangles[3 * i + 2]]);
      if (t >= 0.0f && t <= best.t && rtcd_hit_improves(best, t, (rtcd_int)i)) {
        best.t = t;
        best.triangle = (rtcd_int)i;
      }
    }
    n = node.escape;
  }
  return best;
}

/* As rtcd_brute_nearest, over the tree. */
RTCD_INLINE rtcd_int rtcd_bvh_nearest(rtcd_vec3 point, float radius, RTCD_GLOBAL const rtcd_bvh_node* nodes,
                                      rtcd_uint node_count, RTCD_GLOBAL const rtcd_uint* primitives,
                                      RTCD_GLOBAL const rtcd_vec3* positions,
                                      RTCD_GLOBAL const rtcd_uint* triangles,
                                      RTCD_GLOBAL const rtcd_uchar* zero_area) {
  rtcd_int best = -1;
  float best_d2 = radius * radius;
  rtcd_uint n = 0;
  while (n < node_count) {
    rtcd_bvh_node node = nodes[n];
    rtcd_uint k;
    if (rtcd_box_distance2(point, node.lo, node.hi) * (1.0f - RTCD_BVH_MARGIN) > best_d2) {
      n = node.escape;
      continue;
    }
    if (node.count == 0) {
      n += 1;
      continue;
    }
    for (k = 0; k < node.count; ++k) {
      rtcd_uint i = primitives[node.first + k];
      float d2;
      if (zero_area[i]) continue;
      d2 = rtcd_point_triangle_distance2(point, positions[triangles[3 * i]], positions[triangles[3 * i + 1]],
                                         positions[triangles[3 * i + 2]]);
      if (d2 <= best_d2 && rtcd_nearer(best_d2, best, d2, (rtcd_int)i)) {
        best_d2 = d2;
        best = (rtcd_int)i;
      }
    }
    n = node.escape;
  }
  return best;
}

#endif
