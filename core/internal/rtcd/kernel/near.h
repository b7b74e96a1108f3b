/* Which leaves of a source's tree a full job lists, and the distance bound
 * that search reads: one search that the CPU executors, the OpenCL devices
 * (rtcd_prepare) and the OpenCL host where it places the rays run, so all
 * take the same items, and one bound that DistanceBound::lower is.
 * Contraction is off; sqrt is correctly rounded on both sides. */
#ifndef RTCD_KERNEL_NEAR_H
#define RTCD_KERNEL_NEAR_H

#include "frame.h"
#include "tracer.h"

/* A node of a source's tree: RaySources::Node's layout. An inner node's
 * children are nodes child and child + 1; child 0 marks a leaf. */
typedef struct {
  float lo[3], hi[3];
  rtcd_uint begin, end; /* its items: order[begin, end) */
  rtcd_uint child;
} rtcd_source_node;

/* What a source's tree is searched with: its nodes, the items in tree
 * order (each leaf's in any order), where its edges begin, whether it is a
 * sphere (no edges; its deepest point is an item). */
typedef struct {
  RTCD_GLOBAL const rtcd_source_node* nodes;
  RTCD_GLOBAL const rtcd_uint* order;
  rtcd_uint node_count;
  rtcd_uint first_edge;
  int sphere;
} rtcd_source_tree;

#ifdef RTCD_HAS_DOUBLE
/* rtcd_distance_grid::kind */
#define RTCD_BOUND_GRID 0
#define RTCD_BOUND_SPHERE 1
#define RTCD_BOUND_BOX 2
#define RTCD_BOUND_HALF_SPACE 3

/* A shape's distance bound as DistanceBound holds it, its grid's values apart. */
typedef struct {
  double lo[3], hi[3]; /* a mesh's box; a box's [-h, h] */
  double origin[3];    /* a grid's node (0, 0, 0) */
  double radius;       /* a sphere's */
  double cell;         /* a grid's */
  rtcd_int kind;       /* RTCD_BOUND_* */
  rtcd_int nodes[3];   /* a grid's nodes per axis, x fastest */
} rtcd_distance_grid;

RTCD_INLINE double rtcd_norm3(double x, double y, double z) { return sqrt(x * x + y * y + z * z); }

/* A mesh's grid cell holding p (its node of least coordinates, in c), or 0
 * when p lies beyond the grid (or is NaN). */
RTCD_INLINE int rtcd_grid_cell(const rtcd_distance_grid* g, const double p[3], int c[3]) {
  int a;
  for (a = 0; a < 3; ++a) {
    const double at = (p[a] - g->origin[a]) / g->cell;
    if (!(at >= 0.0 && at <= (double)(g->nodes[a] - 1))) return 0;
    c[a] = (int)at < g->nodes[a] - 2 ? (int)at : g->nodes[a] - 2;
  }
  return 1;
}

/* Corner k (0..7) of cell c: its value, and its distance to p. */
RTCD_INLINE double rtcd_grid_value(const rtcd_distance_grid* g, RTCD_GLOBAL const float* values, const int c[3],
                                   int k) {
  const int x = c[0] + (k & 1), y = c[1] + ((k >> 1) & 1), z = c[2] + ((k >> 2) & 1);
  return (double)values[((rtcd_ulong)z * (rtcd_ulong)g->nodes[1] + (rtcd_ulong)y) * (rtcd_ulong)g->nodes[0] +
                        (rtcd_ulong)x];
}
RTCD_INLINE double rtcd_grid_reach(const rtcd_distance_grid* g, const int c[3], int k, const double p[3]) {
  const int x = c[0] + (k & 1), y = c[1] + ((k >> 1) & 1), z = c[2] + ((k >> 2) & 1);
  return rtcd_norm3(p[0] - (g->origin[0] + g->cell * (double)x), p[1] - (g->origin[1] + g->cell * (double)y),
                    p[2] - (g->origin[2] + g->cell * (double)z));
}

/* p's distance to the box [lo, hi] (0 inside). */
RTCD_INLINE double rtcd_box_distance(const rtcd_distance_grid* g, const double p[3]) {
  double q[3], m;
  int a;
  for (a = 0; a < 3; ++a) {
    m = g->lo[a] - p[a] < p[a] - g->hi[a] ? p[a] - g->hi[a] : g->lo[a] - p[a];
    q[a] = m < 0.0 ? 0.0 : m;
  }
  return rtcd_norm3(q[0], q[1], q[2]);
}

/* A volume's distance from p to its surface, in closed form. */
RTCD_INLINE double rtcd_volume_distance(const rtcd_distance_grid* g, const double p[3]) {
  double q[3], m;
  int a;
  if (g->kind == RTCD_BOUND_SPHERE) return rtcd_abs_d(rtcd_norm3(p[0], p[1], p[2]) - g->radius);
  if (g->kind == RTCD_BOUND_HALF_SPACE) return rtcd_abs_d(p[2]);
  for (a = 0; a < 3; ++a) q[a] = rtcd_abs_d(p[a]) - g->hi[a];
  if (q[0] > 0.0 || q[1] > 0.0 || q[2] > 0.0)
    return rtcd_norm3(q[0] < 0.0 ? 0.0 : q[0], q[1] < 0.0 ? 0.0 : q[1], q[2] < 0.0 ? 0.0 : q[2]);
  m = q[0] < q[1] ? q[1] : q[0];
  return -(m < q[2] ? q[2] : m);
}

/* A lower bound on the distance from p (the shape's frame) to its surface
 * (DistanceBound::lower): closed forms for volumes; for a mesh, the max
 * over p's cell's 8 nodes of the node's value less its distance to p, and
 * never less than p's distance to the mesh's box. */
RTCD_INLINE double rtcd_distance_lower(const rtcd_distance_grid* g, RTCD_GLOBAL const float* values,
                                       const double p[3]) {
  double best, d;
  int c[3], k;
  if (g->kind != RTCD_BOUND_GRID) return rtcd_volume_distance(g, p);
  best = rtcd_box_distance(g, p);
  if (!rtcd_grid_cell(g, p, c)) return best;
  for (k = 0; k < 8; ++k) {
    d = rtcd_grid_value(g, values, c, k) - rtcd_grid_reach(g, c, k, p);
    best = best < d ? d : best;
  }
  return best - 1e-9 * g->cell; /* the lookup's own rounding */
}

/* Whether rtcd_distance_lower(g, values, p) > threshold, the same answer
 * for less: subtracting the rounding allowance keeps order, so the bound
 * passes the threshold when any node's term less the allowance does; a
 * node whose value less the allowance does not cannot (its distance to p
 * only lowers it), and needs no square root. */
RTCD_INLINE int rtcd_distance_exceeds(const rtcd_distance_grid* g, RTCD_GLOBAL const float* values,
                                      const double p[3], double threshold) {
  const double allowance = 1e-9 * g->cell;
  double outside, value;
  int c[3], k;
  if (g->kind != RTCD_BOUND_GRID) return rtcd_volume_distance(g, p) > threshold;
  outside = rtcd_box_distance(g, p);
  if (!rtcd_grid_cell(g, p, c)) return outside > threshold;
  if (outside - allowance > threshold) return 1;
  for (k = 0; k < 8; ++k) {
    value = rtcd_grid_value(g, values, c, k);
    if (!(value - allowance > threshold)) continue;
    if ((value - rtcd_grid_reach(g, c, k, p)) - allowance > threshold) return 1;
  }
  return 0;
}

#define RTCD_NEAR_STACK 64 /* depth <= log2(origins) + 1 for median splits */
#define RTCD_NO_LEAF 0xffffffffu

/* A job's search for the leaves of its source's tree whose box, placed in
 * the target's frame as the box around it (in double, grown well past
 * rounding), meets the job's candidate box; a node of edges is turned away
 * too when the target's distance bound at its centre, less half its box's
 * diagonal, puts every edge in it beyond `reach` of the surface (negative:
 * the job tests no edge). */
typedef struct {
  double rotation[9], spread[9], translation[3];
  double lo[3], hi[3];
  double reach, beyond;
  rtcd_uint stack[RTCD_NEAR_STACK];
  int top;
} rtcd_near_search;

/* How far from the target's surface a full job's edges are still worth
 * testing: those that cannot cross it now are dropped, and of the others
 * only those within the watch reach are kept for later walks
 * (rtcd_watch_edge), which stop once the pair has moved that far.
 * Negative: the job tests no edge. */
RTCD_INLINE double rtcd_edge_reach(const rtcd_trace_params* p) {
  return !p->edges ? -1.0 : p->watch ? (double)p->reach : 0.0;
}

RTCD_INLINE double rtcd_max_abs3(const double v[3]) {
  const double a = rtcd_abs_d(v[0]), b = rtcd_abs_d(v[1]), c = rtcd_abs_d(v[2]);
  const double m = a < b ? b : a;
  return m < c ? c : m;
}

/* The search of the job framed by f (its transform and candidate box). */
RTCD_INLINE void rtcd_near_begin(rtcd_near_search* s, const rtcd_frame* f, double reach,
                                 const rtcd_source_tree* tree) {
  const double scale = 1.0 + rtcd_norm3(f->translation[0], f->translation[1], f->translation[2]) +
                       rtcd_max_abs3(f->lo) + rtcd_max_abs3(f->hi);
  int i;
  for (i = 0; i < 9; ++i) {
    s->rotation[i] = f->rotation[i];
    s->spread[i] = rtcd_abs_d(f->rotation[i]);
  }
  for (i = 0; i < 3; ++i) {
    s->translation[i] = f->translation[i];
    s->lo[i] = f->lo[i] - 1e-9 * scale;
    s->hi[i] = f->hi[i] + 1e-9 * scale;
  }
  s->reach = reach;
  s->beyond = reach + 1e-6 * scale; /* far above the float rounding of the kernel's edge tests */
  s->top = 0;
  if (tree->node_count > 0 && !(f->lo[0] > f->hi[0] || f->lo[1] > f->hi[1] || f->lo[2] > f->hi[2]))
    s->stack[s->top++] = 0;
}

/* Row i of the search's box test: node n's centre (mid, in the source's
 * frame) placed on axis i of the target's, in *centre; whether the node's
 * placed box (half extent `extent`) meets the candidate box on that axis.
 * Scalars, not arrays: the kernel compiler keeps them in registers. */
RTCD_INLINE int rtcd_near_axis(const rtcd_near_search* s, int i, double mid_x, double mid_y, double mid_z,
                               double extent_x, double extent_y, double extent_z, double* centre) {
  const double* r = s->rotation + 3 * i;
  const double* a = s->spread + 3 * i;
  const double h = a[0] * extent_x + a[1] * extent_y + a[2] * extent_z;
  *centre = r[0] * mid_x + r[1] * mid_y + r[2] * mid_z + s->translation[i];
  return *centre + h >= s->lo[i] && *centre - h <= s->hi[i];
}

/* Whether node n's items may include a candidate of the search's job. */
RTCD_INLINE int rtcd_near_may_hold(const rtcd_near_search* s, const rtcd_source_tree* tree,
                                   const rtcd_distance_grid* target, RTCD_GLOBAL const float* values,
                                   const rtcd_source_node* n) {
  const double mid_x = 0.5 * ((double)n->lo[0] + (double)n->hi[0]);
  const double mid_y = 0.5 * ((double)n->lo[1] + (double)n->hi[1]);
  const double mid_z = 0.5 * ((double)n->lo[2] + (double)n->hi[2]);
  const double extent_x = 0.5 * (double)(n->hi[0] - n->lo[0]);
  const double extent_y = 0.5 * (double)(n->hi[1] - n->lo[1]);
  const double extent_z = 0.5 * (double)(n->hi[2] - n->lo[2]);
  double centre[3];
  if (!rtcd_near_axis(s, 0, mid_x, mid_y, mid_z, extent_x, extent_y, extent_z, &centre[0]) ||
      !rtcd_near_axis(s, 1, mid_x, mid_y, mid_z, extent_x, extent_y, extent_z, &centre[1]) ||
      !rtcd_near_axis(s, 2, mid_x, mid_y, mid_z, extent_x, extent_y, extent_z, &centre[2]))
    return 0;
  /* edges only: no origin, no sphere item */
  if (tree->sphere || !(n->begin < n->end && tree->order[n->begin] >= tree->first_edge &&
                        tree->order[n->end - 1] >= tree->first_edge))
    return 1;
  /* half the box's diagonal: exactly 0.5 * |hi - lo|, as halving is exact */
  return s->reach >= 0.0 &&
         !rtcd_distance_exceeds(target, values, centre, rtcd_norm3(extent_x, extent_y, extent_z) + s->beyond);
}

/* The search's next leaf, or RTCD_NO_LEAF: each leaf at most once. */
RTCD_INLINE rtcd_uint rtcd_near_next(rtcd_near_search* s, const rtcd_source_tree* tree,
                                     const rtcd_distance_grid* target, RTCD_GLOBAL const float* values) {
  while (s->top > 0) {
    const rtcd_uint index = s->stack[--s->top];
    const rtcd_source_node n = tree->nodes[index];
    if (!rtcd_near_may_hold(s, tree, target, values, &n)) continue;
    if (n.child != 0) {
      s->stack[s->top++] = n.child;
      s->stack[s->top++] = n.child + 1;
      continue;
    }
    return index;
  }
  return RTCD_NO_LEAF;
}
#endif

#endif
