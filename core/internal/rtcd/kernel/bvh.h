/* Traversal of a bounding-volume hierarchy, binary and flattened depth
 * first (a node's first child is the next node, and `escape` is the node
 * after its subtree: for a first child, its sibling), and the same tree
 * collapsed to RTCD_BVH_WIDTH children a node, whose boxes are tested
 * together. The wide tree is the one traversed; the binary one serves
 * where the stack runs out. The answers follow the tie rules of tracer.h
 * whatever the tree and the visiting order: boxes are pruned only when
 * they cannot hold a hit as near as the best one, with margins wider than
 * the rounding of the box tests. */
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

/* A leaf's triangle as the traversal reads it: its id and its corners in
 * the triangle's order, in place, so a leaf costs one load a triangle, not
 * three dependent ones. Zero-area triangles, which no query answers, are
 * left out of the tree. */
typedef struct {
  rtcd_vec3 corner[3];
  rtcd_int triangle;
} rtcd_bvh_primitive;

/* A wide node: up to RTCD_BVH_WIDTH children, their boxes by axis so that
 * one slab test covers them all. A child is another wide node (>= 0), none
 * (-1), or a leaf, -2 - (first * 4 + count): `first` in the primitive
 * list, count < 4. `subtree` is the binary node rooting the child's
 * subtree. The host's builder and the kernels read the same width. */
#define RTCD_BVH_WIDTH 4
typedef struct {
  float lo_x[RTCD_BVH_WIDTH], lo_y[RTCD_BVH_WIDTH], lo_z[RTCD_BVH_WIDTH];
  float hi_x[RTCD_BVH_WIDTH], hi_y[RTCD_BVH_WIDTH], hi_z[RTCD_BVH_WIDTH];
  rtcd_int child[RTCD_BVH_WIDTH];
  rtcd_uint subtree[RTCD_BVH_WIDTH];
} rtcd_bvh_wide_node;

#ifdef __OPENCL_C_VERSION__
/* OpenCL's vectors of a wide node's width. */
#if RTCD_BVH_WIDTH == 8
typedef float8 rtcd_floatw;
typedef int8 rtcd_intw;
#define RTCD_VLOADW vload8
#define RTCD_VSTOREW vstore8
#else
typedef float4 rtcd_floatw;
typedef int4 rtcd_intw;
#define RTCD_VLOADW vload4
#define RTCD_VSTOREW vstore4
#endif
#endif
#define RTCD_BVH_NO_CHILD (-1)
#define RTCD_BVH_LEAF(first, count) (-2 - (rtcd_int)((first) * 4u + (count)))
#define RTCD_BVH_LEAF_FIRST(code) ((rtcd_uint)(-2 - (code)) / 4u)
#define RTCD_BVH_LEAF_COUNT(code) ((rtcd_uint)(-2 - (code)) % 4u)

#ifdef __OPENCL_C_VERSION__
/* Which of a wide node's children exist, a lane each. */
RTCD_ALWAYS_INLINE rtcd_intw rtcd_children_wide(RTCD_GLOBAL const rtcd_bvh_wide_node* node) {
  return RTCD_VLOADW(0, node->child) != (rtcd_intw)(RTCD_BVH_NO_CHILD);
}
#endif

/* Relative margin on box distances: a few hundred float ulps, far more than
 * the box tests round. */
#define RTCD_BVH_MARGIN 1.0e-5f

/* Branch-free selections (the compilers' min and max instructions). */
#define RTCD_MIN(x, y) ((x) < (y) ? (x) : (y))
#define RTCD_MAX(x, y) ((x) > (y) ? (x) : (y))

/* Where the ray's line enters the box within [0, t_max], or -1 when it
 * does not meet it there: slabs by division (correctly rounded), each end
 * widened by the margin. */
RTCD_INLINE float rtcd_ray_box_entry(const rtcd_ray* ray, rtcd_vec3 lo, rtcd_vec3 hi, float t_max) {
  float t_near = 0.0f, t_far = t_max;
  int k;
  for (k = 0; k < 3; ++k) {
    float o = rtcd_component(ray->origin, k), d = rtcd_component(ray->direction, k);
    float l = rtcd_component(lo, k), h = rtcd_component(hi, k);
    float t0, t1, a, b;
    if (d == 0.0f) {
      if (o < l || o > h) return -1.0f;
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
    if (t_near > t_far) return -1.0f;
  }
  return t_near;
}

/* A ray as the slab tests read it: the inverse of each direction
 * component, so a box costs products and no branch. A product rounds twice
 * where a quotient rounds once, both far inside the margin. `divide` is set
 * where an inverse would not serve (a zero or subnormal component): such a
 * ray is tested by division. */
typedef struct {
  const rtcd_ray* ray;
  rtcd_vec3 inverse;
  int divide;
} rtcd_slab_ray;

RTCD_INLINE int rtcd_slab_divides(float d, float inverse) { return d == 0.0f || RTCD_FABS(inverse) > 3.0e38f; }

/* The inverses as scalars, not through an array: read back whole, an
 * array's separate stores would stall the first box test. */
RTCD_INLINE rtcd_slab_ray rtcd_make_slab_ray(const rtcd_ray* ray) {
  rtcd_slab_ray s;
  const rtcd_vec3 d = ray->direction;
  const float x = d.x == 0.0f ? 0.0f : 1.0f / d.x, y = d.y == 0.0f ? 0.0f : 1.0f / d.y,
              z = d.z == 0.0f ? 0.0f : 1.0f / d.z;
  s.ray = ray;
  s.inverse = rtcd_v3(x, y, z);
  s.divide = rtcd_slab_divides(d.x, x) | rtcd_slab_divides(d.y, y) | rtcd_slab_divides(d.z, z);
  return s;
}

/* As rtcd_ray_box_entry, by the inverses. Widening is monotone, so the
 * margin applies once to the nearest and farthest slab ends, exactly as it
 * would to every end before they are compared. */
RTCD_ALWAYS_INLINE float rtcd_slab_entry(const rtcd_slab_ray* s, rtcd_vec3 lo, rtcd_vec3 hi, float t_max) {
  rtcd_vec3 o = s->ray->origin, inv = s->inverse;
  float x0, x1, y0, y1, z0, z1, a, b;
  if (s->divide) return rtcd_ray_box_entry(s->ray, lo, hi, t_max);
  x0 = (lo.x - o.x) * inv.x;
  x1 = (hi.x - o.x) * inv.x;
  y0 = (lo.y - o.y) * inv.y;
  y1 = (hi.y - o.y) * inv.y;
  z0 = (lo.z - o.z) * inv.z;
  z1 = (hi.z - o.z) * inv.z;
  a = RTCD_MAX(RTCD_MAX(RTCD_MIN(x0, x1), RTCD_MIN(y0, y1)), RTCD_MAX(RTCD_MIN(z0, z1), 0.0f));
  b = RTCD_MIN(RTCD_MAX(x0, x1), RTCD_MIN(RTCD_MAX(y0, y1), RTCD_MAX(z0, z1)));
  a -= a * RTCD_BVH_MARGIN; /* a >= 0 */
  b += RTCD_FABS(b) * RTCD_BVH_MARGIN;
  b = RTCD_MIN(b, t_max);
  return a <= b ? a : -1.0f;
}

/* Squared distance from a point to a box (0 inside). */
RTCD_ALWAYS_INLINE float rtcd_box_distance2(rtcd_vec3 p, rtcd_vec3 lo, rtcd_vec3 hi) {
  float d2 = 0.0f;
  int k;
  for (k = 0; k < 3; ++k) {
    float c = rtcd_component(p, k), l = rtcd_component(lo, k), h = rtcd_component(hi, k);
    float d = RTCD_MAX(RTCD_MAX(l - c, c - h), 0.0f);
    d2 += d * d;
  }
  return d2;
}

/* Nearer children first: a short stack of the farther ones, each with its
 * entry distance (a ray's t, a point's squared distance), so a subtree
 * pushed before a nearer hit was found is dropped when popped. Pruning with
 * the best so far is the same test whenever it runs, so the order changes
 * the work, not the answer. Past a full stack, a subtree is traversed at
 * once, in its own depth-first order by the binary tree's escape links. */
#ifndef RTCD_BVH_STACK
#define RTCD_BVH_STACK 32
#endif

/* A wide node's child boxes against the ray, each entry as
 * rtcd_slab_entry's (-1: missed, or no child); OpenCL tests them all at
 * once. */
RTCD_ALWAYS_INLINE void rtcd_slab_entries_wide(const rtcd_slab_ray* s, RTCD_GLOBAL const rtcd_bvh_wide_node* node,
                                           float t_max, float* entry) {
  int k;
#ifdef __OPENCL_C_VERSION__
  if (!s->divide) {
    const rtcd_floatw zero = (rtcd_floatw)(0.0f);
    rtcd_vec3 o = s->ray->origin, inv = s->inverse;
    rtcd_floatw x0 = (RTCD_VLOADW(0, node->lo_x) - o.x) * inv.x, x1 = (RTCD_VLOADW(0, node->hi_x) - o.x) * inv.x;
    rtcd_floatw y0 = (RTCD_VLOADW(0, node->lo_y) - o.y) * inv.y, y1 = (RTCD_VLOADW(0, node->hi_y) - o.y) * inv.y;
    rtcd_floatw z0 = (RTCD_VLOADW(0, node->lo_z) - o.z) * inv.z, z1 = (RTCD_VLOADW(0, node->hi_z) - o.z) * inv.z;
    rtcd_floatw a = RTCD_MAX(RTCD_MAX(RTCD_MIN(x0, x1), RTCD_MIN(y0, y1)), RTCD_MAX(RTCD_MIN(z0, z1), zero));
    rtcd_floatw b = RTCD_MIN(RTCD_MAX(x0, x1), RTCD_MIN(RTCD_MAX(y0, y1), RTCD_MAX(z0, z1)));
    a -= a * RTCD_BVH_MARGIN;
    b += fabs(b) * RTCD_BVH_MARGIN;
    b = RTCD_MIN(b, (rtcd_floatw)(t_max));
    RTCD_VSTOREW(select((rtcd_floatw)(-1.0f), a, (a <= b) & rtcd_children_wide(node)), 0, entry);
    return;
  }
#endif
  for (k = 0; k < RTCD_BVH_WIDTH; ++k)
    entry[k] = node->child[k] == RTCD_BVH_NO_CHILD
                   ? -1.0f
                   : rtcd_slab_entry(s, rtcd_v3(node->lo_x[k], node->lo_y[k], node->lo_z[k]),
                                     rtcd_v3(node->hi_x[k], node->hi_y[k], node->hi_z[k]), t_max);
}

/* Whether a box at squared distance d2 may hold a triangle as near as the
 * best: the margin keeps ties. */
RTCD_INLINE int rtcd_bvh_box_near(float d2, float best_d2) { return d2 * (1.0f - RTCD_BVH_MARGIN) <= best_d2; }

/* A wide node's child boxes: squared distances from the point, as
 * rtcd_box_distance2's (-1: too far for the best, or no child); OpenCL
 * measures them all at once. */
RTCD_ALWAYS_INLINE void rtcd_box_near_wide(rtcd_vec3 p, RTCD_GLOBAL const rtcd_bvh_wide_node* node, float best_d2,
                                       float* d2) {
#ifdef __OPENCL_C_VERSION__
  const rtcd_floatw zero = (rtcd_floatw)(0.0f);
  rtcd_floatw dx = RTCD_MAX(RTCD_MAX(RTCD_VLOADW(0, node->lo_x) - p.x, p.x - RTCD_VLOADW(0, node->hi_x)), zero);
  rtcd_floatw dy = RTCD_MAX(RTCD_MAX(RTCD_VLOADW(0, node->lo_y) - p.y, p.y - RTCD_VLOADW(0, node->hi_y)), zero);
  rtcd_floatw dz = RTCD_MAX(RTCD_MAX(RTCD_VLOADW(0, node->lo_z) - p.z, p.z - RTCD_VLOADW(0, node->hi_z)), zero);
  rtcd_floatw d = dx * dx + dy * dy + dz * dz;
  RTCD_VSTOREW(select((rtcd_floatw)(-1.0f), d,
                      (d * (1.0f - RTCD_BVH_MARGIN) <= best_d2) & rtcd_children_wide(node)),
          0, d2);
#else
  int k;
  for (k = 0; k < RTCD_BVH_WIDTH; ++k) {
    d2[k] = rtcd_box_distance2(p, rtcd_v3(node->lo_x[k], node->lo_y[k], node->lo_z[k]),
                               rtcd_v3(node->hi_x[k], node->hi_y[k], node->hi_z[k]));
    if (node->child[k] == RTCD_BVH_NO_CHILD || !rtcd_bvh_box_near(d2[k], best_d2)) d2[k] = -1.0f;
  }
#endif
}

/* The children to visit (key >= 0), nearest first; returns how many. */
RTCD_ALWAYS_INLINE int rtcd_bvh_order(const float* key, int* order) {
  int hits = 0, k, h;
  for (k = 0; k < RTCD_BVH_WIDTH; ++k) {
    if (key[k] < 0.0f) continue;
    for (h = hits; h > 0 && key[order[h - 1]] > key[k]; --h) order[h] = order[h - 1];
    order[h] = k;
    ++hits;
  }
  return hits;
}

/* A leaf's triangles against the best hit so far. */
RTCD_ALWAYS_INLINE void rtcd_bvh_leaf_first_hit(const rtcd_ray* ray, rtcd_uint first, rtcd_uint count,
                                                RTCD_GLOBAL const rtcd_bvh_primitive* primitives, rtcd_hit* best) {
  rtcd_uint k;
  for (k = 0; k < count; ++k) {
    const rtcd_bvh_primitive p = primitives[first + k];
    const float t = rtcd_hit_distance(ray, p.corner[0], p.corner[1], p.corner[2]);
    if (t >= 0.0f && t <= best->t && rtcd_hit_improves(*best, t, p.triangle)) {
      best->t = t;
      best->triangle = p.triangle;
    }
  }
}

/* The binary nodes [n, end) of a subtree in depth-first order, no stack. */
RTCD_INLINE void rtcd_bvh_range_first_hit(const rtcd_slab_ray* slabs, RTCD_GLOBAL const rtcd_bvh_node* nodes,
                                          rtcd_uint n, rtcd_uint end, RTCD_GLOBAL const rtcd_bvh_primitive* primitives,
                                          rtcd_hit* best) {
  while (n < end) {
    rtcd_bvh_node node = nodes[n];
    if (rtcd_slab_entry(slabs, node.lo, node.hi, best->t) < 0.0f) {
      n = node.escape;
    } else if (node.count == 0) {
      n += 1;
    } else {
      rtcd_bvh_leaf_first_hit(slabs->ray, node.first, node.count, primitives, best);
      n = node.escape;
    }
  }
}

/* As rtcd_brute_first_hit, over the wide tree. */
RTCD_INLINE rtcd_hit rtcd_bvh_first_hit(const rtcd_ray* ray, RTCD_GLOBAL const rtcd_bvh_node* nodes,
                                        rtcd_uint node_count, RTCD_GLOBAL const rtcd_bvh_wide_node* wide,
                                        RTCD_GLOBAL const rtcd_bvh_primitive* primitives, float t_max) {
  rtcd_slab_ray slabs = rtcd_make_slab_ray(ray);
  rtcd_hit best;
  rtcd_int stack[RTCD_BVH_STACK];
  float entry[RTCD_BVH_STACK];
  int top = 1;
  best.triangle = -1;
  best.t = t_max;
  if (node_count == 0) return best;
  stack[0] = 0; /* the root: its children's boxes are tested */
  entry[0] = 0.0f;
  while (top > 0) {
    rtcd_int code;
    --top;
    if (entry[top] > best.t) continue;
    code = stack[top];
    while (code >= 0) { /* a wide node: the children the ray meets, the nearest next */
      RTCD_GLOBAL const rtcd_bvh_wide_node* node = wide + code;
      float t[RTCD_BVH_WIDTH];
      int order[RTCD_BVH_WIDTH], hits, h, k;
      rtcd_slab_entries_wide(&slabs, node, best.t, t);
      hits = rtcd_bvh_order(t, order);
      code = RTCD_BVH_NO_CHILD;
      if (hits == 0) break;
      for (h = hits - 1; h > 0; --h) {
        rtcd_int c;
        k = order[h];
        c = node->child[k];
        if (top < RTCD_BVH_STACK) {
          stack[top] = c;
          entry[top] = t[k];
          ++top;
        } else if (c >= 0) {
          rtcd_bvh_range_first_hit(&slabs, nodes, node->subtree[k], nodes[node->subtree[k]].escape, primitives,
                                   &best);
        } else {
          rtcd_bvh_leaf_first_hit(ray, RTCD_BVH_LEAF_FIRST(c), RTCD_BVH_LEAF_COUNT(c), primitives, &best);
        }
      }
      code = node->child[order[0]];
    }
    if (code <= -2)
      rtcd_bvh_leaf_first_hit(ray, RTCD_BVH_LEAF_FIRST(code), RTCD_BVH_LEAF_COUNT(code), primitives, &best);
  }
  return best;
}

/* A leaf's triangles against the nearest so far. */
RTCD_ALWAYS_INLINE void rtcd_bvh_leaf_nearest(rtcd_vec3 point, rtcd_uint first, rtcd_uint count,
                                              RTCD_GLOBAL const rtcd_bvh_primitive* primitives, rtcd_int* best,
                                              float* best_d2) {
  rtcd_uint k;
  for (k = 0; k < count; ++k) {
    const rtcd_bvh_primitive p = primitives[first + k];
    const float d2 = rtcd_point_triangle_distance2(point, p.corner[0], p.corner[1], p.corner[2]);
    if (d2 <= *best_d2 && rtcd_nearer(*best_d2, *best, d2, p.triangle)) {
      *best_d2 = d2;
      *best = p.triangle;
    }
  }
}

/* The binary nodes [n, end) of a subtree in depth-first order, no stack. */
RTCD_INLINE void rtcd_bvh_range_nearest(rtcd_vec3 point, RTCD_GLOBAL const rtcd_bvh_node* nodes, rtcd_uint n,
                                        rtcd_uint end, RTCD_GLOBAL const rtcd_bvh_primitive* primitives, rtcd_int* best,
                                        float* best_d2) {
  while (n < end) {
    rtcd_bvh_node node = nodes[n];
    if (!rtcd_bvh_box_near(rtcd_box_distance2(point, node.lo, node.hi), *best_d2)) {
      n = node.escape;
    } else if (node.count == 0) {
      n += 1;
    } else {
      rtcd_bvh_leaf_nearest(point, node.first, node.count, primitives, best, best_d2);
      n = node.escape;
    }
  }
}

/* As rtcd_brute_nearest, over the wide tree; or, when enough > 0, the
 * first triangle found within enough of the point (tracer.h's contract). */
RTCD_INLINE rtcd_int rtcd_bvh_nearest(rtcd_vec3 point, float radius, float enough,
                                      RTCD_GLOBAL const rtcd_bvh_node* nodes, rtcd_uint node_count,
                                      RTCD_GLOBAL const rtcd_bvh_wide_node* wide,
                                      RTCD_GLOBAL const rtcd_bvh_primitive* primitives) {
  rtcd_int best = -1;
  float best_d2 = radius * radius, enough_d2 = enough > 0.0f ? enough * enough : -1.0f;
  rtcd_int stack[RTCD_BVH_STACK];
  float distance2[RTCD_BVH_STACK];
  int top = 1;
  if (node_count == 0) return best;
  stack[0] = 0; /* the root: its children's boxes are measured */
  distance2[0] = 0.0f;
  while (top > 0) {
    rtcd_int code;
    --top;
    if (!rtcd_bvh_box_near(distance2[top], best_d2)) continue;
    code = stack[top];
    while (code >= 0) { /* a wide node: the children that may hold the nearest, the nearest next */
      RTCD_GLOBAL const rtcd_bvh_wide_node* node = wide + code;
      float d2[RTCD_BVH_WIDTH];
      int order[RTCD_BVH_WIDTH], hits, h, k;
      rtcd_box_near_wide(point, node, best_d2, d2);
      hits = rtcd_bvh_order(d2, order);
      code = RTCD_BVH_NO_CHILD;
      if (hits == 0) break;
      for (h = hits - 1; h > 0; --h) {
        rtcd_int c;
        k = order[h];
        c = node->child[k];
        if (top < RTCD_BVH_STACK) {
          stack[top] = c;
          distance2[top] = d2[k];
          ++top;
        } else if (c >= 0) {
          rtcd_bvh_range_nearest(point, nodes, node->subtree[k], nodes[node->subtree[k]].escape, primitives, &best,
                                 &best_d2);
        } else {
          rtcd_bvh_leaf_nearest(point, RTCD_BVH_LEAF_FIRST(c), RTCD_BVH_LEAF_COUNT(c), primitives, &best, &best_d2);
        }
      }
      code = node->child[order[0]];
    }
    if (code <= -2) {
      rtcd_bvh_leaf_nearest(point, RTCD_BVH_LEAF_FIRST(code), RTCD_BVH_LEAF_COUNT(code), primitives, &best, &best_d2);
      if (best_d2 <= enough_d2) break;
    }
  }
  return best;
}

#endif
