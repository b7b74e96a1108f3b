/* What every executor hands to and gets from the per-ray code of trace.h:
 * candidate rays, per-job parameters, outcomes, the placement of a ray
 * origin in the target's frame, and the tie rules of the full tracers. */
#ifndef RTCD_KERNEL_TRACER_H
#define RTCD_KERNEL_TRACER_H

#include "frame.h"
#include "types.h"

/* What a target is, for the executors' dispatch (a mesh, or a volume of volumes.h). */
#define RTCD_TARGET_MESH 0
#define RTCD_TARGET_SPHERE 1
#define RTCD_TARGET_BOX 2
#define RTCD_TARGET_HALFSPACE 3

/* First hit of a ray with a mesh; triangle -1: nothing within range. */
typedef struct {
  rtcd_int triangle;
  float t;
} rtcd_hit;

/* What a source item is (rtcd_outcome::edge). */
#define RTCD_ITEM_ORIGIN 0
#define RTCD_ITEM_EDGE 1
#define RTCD_ITEM_SPHERE 2

/* A candidate ray in the target's frame, rounded to floats. An edge item
 * is a candidate too: origin is one end, direction runs to the other. */
typedef struct {
  rtcd_uint vertex; /* the source's item: a ray origin, or an edge from first_edge on */
  rtcd_int start; /* iterative: the exit walk's first triangle (-1: look up the nearest) */
  rtcd_int entry; /* iterative: the entry walk's first triangle (-1: unknown) */
  rtcd_uint job;  /* the job's index in its batch (device executors) */
  rtcd_vec3 origin;
  rtcd_vec3 direction;
} rtcd_candidate;

/* What one candidate ray found (rtcd::RayOutcome on the host). */
typedef struct {
  rtcd_uint vertex;
  rtcd_int triangle;        /* the face it leaves through, or where the next walk starts; -1: none */
  rtcd_int entry;           /* penetrating rays: the face the line entered through behind the vertex; -1 unknown */
  float t;                  /* float distance along the ray (negative: predictive) */
  rtcd_uint walk_steps;     /* iterative rays: triangles the walks located */
  rtcd_uchar kind;          /* an rtcd_ray_kind; WATCHED is tracked but not reported */
  rtcd_uchar status;        /* an rtcd_line_status (iterative rays and volumes) */
  rtcd_uchar predictive_cast; /* an outward ray was traced too */
  rtcd_uchar nearest_query; /* a nearest-triangle query was made */
  rtcd_uchar retraced;      /* iterative: the walks could not be trusted (rtcd_walked_kind), traced again */
  rtcd_uchar fold_cast;     /* iterative: the fold check cast a ray (the contact lies beyond its face's clearance) */
  rtcd_uchar edge;          /* RTCD_ITEM_EDGE: vertex is the edge's item, t the contact's place along it;
                               RTCD_ITEM_SPHERE: a sphere's deepest point (rtcd_sphere_trace); 0: a ray origin */
  rtcd_uchar edge_rays;     /* edge items: rays the crossing test cast */
  rtcd_int nearest;         /* penetrating rays against a mesh (rtcd_trace_params::nearest_surface): the
                               target's triangle nearest the origin, the contact's way out; -1 none */
} rtcd_outcome;

/* One job's parameters, the same for all of its rays. */
typedef struct {
  /* The target's box grown by the watch reach, each bound rounded outward
   * to float: a float origin lies in this box exactly when it lies in the
   * double-precision box, so no device needs doubles for the test. */
  rtcd_vec3 watch_lo;
  rtcd_vec3 watch_hi;
  float extension; /* distance_extension */
  float reach;     /* the watch reach: the nearest-triangle query's radius */
  rtcd_uint max_walk_steps;
  rtcd_int predictive;
  rtcd_int watch; /* vertices near the target are watched (predictive rays on, not Mode::full) */
  rtcd_int iterative;
  rtcd_int verify; /* walked contacts are checked for a fold between their entry and exit faces */
  rtcd_uint first_edge; /* the source's items from here on are edges, or a sphere's one deepest-point item */
  rtcd_int edges;       /* those items are candidates (Config::edge_contacts) */
  float source_radius;  /* a sphere source: its radius; 0 otherwise */
  float moved;          /* iterative jobs: the pair's motion since its full step (equation 2.1), rounded up */
  rtcd_int nearest_surface; /* contacts take the target's nearest triangle as their way out (Config::nearest_surface) */
} rtcd_trace_params;

RTCD_INLINE void rtcd_outcome_init(rtcd_outcome* o, rtcd_uint vertex) {
  o->vertex = vertex;
  o->triangle = -1;
  o->entry = -1;
  o->t = 0.0f;
  o->walk_steps = 0;
  o->kind = 0;
  o->status = 0;
  o->predictive_cast = 0;
  o->nearest_query = 0;
  o->retraced = 0;
  o->fold_cast = 0;
  o->edge = RTCD_ITEM_ORIGIN;
  o->edge_rays = 0;
  o->nearest = -1;
}

/* The rtcd_outcome::edge a job's item gets: which test the executors'
 * dispatch runs it through. Items from first_edge on are edges, tested by
 * rtcd_edge_trace against a mesh; against a volume, a sphere source's item
 * is its deepest point (rtcd_sphere_trace), any other an edge. */
RTCD_INLINE int rtcd_item_kind(int target_kind, const rtcd_trace_params* p, rtcd_uint item) {
  if (item < p->first_edge) return RTCD_ITEM_ORIGIN;
  return target_kind != RTCD_TARGET_MESH && p->source_radius > 0.0f ? RTCD_ITEM_SPHERE : RTCD_ITEM_EDGE;
}

RTCD_INLINE int rtcd_inside_box(rtcd_vec3 p, rtcd_vec3 lo, rtcd_vec3 hi) {
  return p.x >= lo.x && p.y >= lo.y && p.z >= lo.z && p.x <= hi.x && p.y <= hi.y && p.z <= hi.z;
}

/* The tie rules of the full tracers, whatever order they visit triangles
 * in: the nearest hit within t_max, the lowest triangle id among equal
 * distances (equally for the nearest triangle to a point). */
RTCD_INLINE int rtcd_hit_improves(rtcd_hit best, float t, rtcd_int triangle) {
  return t < best.t || (t == best.t && (best.triangle < 0 || triangle < best.triangle));
}
RTCD_INLINE int rtcd_nearer(float best_d2, rtcd_int best, float d2, rtcd_int triangle) {
  return d2 < best_d2 || (d2 == best_d2 && (best < 0 || triangle < best));
}

#ifdef RTCD_HAS_DOUBLE
/* Places a source vertex's ray in the target's frame: the origin in double
 * (rotation, then translation), tested against the candidate box in double,
 * then rounded to float with its direction. 0: not a candidate (no
 * direction, or outside the box). */
RTCD_INLINE int rtcd_place_ray(RTCD_GLOBAL const rtcd_frame* f, rtcd_vec3 origin, rtcd_vec3 direction,
                               rtcd_vec3* origin_out, rtcd_vec3* direction_out) {
  double ox = origin.x, oy = origin.y, oz = origin.z;
  double dx = direction.x, dy = direction.y, dz = direction.z;
  double px, py, pz;
  if (direction.x == 0.0f && direction.y == 0.0f && direction.z == 0.0f) return 0; /* a vertex with no normal */
  px = f->rotation[0] * ox + f->rotation[1] * oy + f->rotation[2] * oz + f->translation[0];
  py = f->rotation[3] * ox + f->rotation[4] * oy + f->rotation[5] * oz + f->translation[1];
  pz = f->rotation[6] * ox + f->rotation[7] * oy + f->rotation[8] * oz + f->translation[2];
  if (!(px >= f->lo[0] && py >= f->lo[1] && pz >= f->lo[2] && px <= f->hi[0] && py <= f->hi[1] && pz <= f->hi[2]))
    return 0;
  *origin_out = rtcd_v3((float)px, (float)py, (float)pz);
  *direction_out = rtcd_v3((float)(f->rotation[0] * dx + f->rotation[1] * dy + f->rotation[2] * dz),
                           (float)(f->rotation[3] * dx + f->rotation[4] * dy + f->rotation[5] * dz),
                           (float)(f->rotation[6] * dx + f->rotation[7] * dy + f->rotation[8] * dz));
  return 1;
}

/* Places an edge item (origin: one end; along: to the other end) in the
 * target's frame in double, like rtcd_place_ray; a candidate when the
 * segment meets the candidate box (slabs in double). 0: not a candidate
 * (zero length, or the segment misses the box). */
RTCD_INLINE int rtcd_place_edge(RTCD_GLOBAL const rtcd_frame* f, rtcd_vec3 origin, rtcd_vec3 along,
                                rtcd_vec3* origin_out, rtcd_vec3* along_out) {
  double p[3], d[3];
  double s0 = 0.0, s1 = 1.0;
  int k, across = 0;
  if (along.x == 0.0f && along.y == 0.0f && along.z == 0.0f) return 0;
  for (k = 0; k < 3; ++k) {
    p[k] = f->rotation[3 * k] * origin.x + f->rotation[3 * k + 1] * origin.y + f->rotation[3 * k + 2] * origin.z +
           f->translation[k];
    d[k] = f->rotation[3 * k] * along.x + f->rotation[3 * k + 1] * along.y + f->rotation[3 * k + 2] * along.z;
  }
  /* Most edges lie wholly inside the box or wholly beside one of its faces:
   * their ends settle it; only an edge across a face needs the slabs. */
  for (k = 0; k < 3; ++k) {
    double q = p[k] + d[k];
    double low = q < p[k] ? q : p[k], high = q < p[k] ? p[k] : q;
    if (high < f->lo[k] || low > f->hi[k]) return 0;
    across = across || low < f->lo[k] || high > f->hi[k];
  }
  for (k = 0; across && k < 3; ++k) {
    if (d[k] != 0.0) {
      double a = (f->lo[k] - p[k]) / d[k], b = (f->hi[k] - p[k]) / d[k];
      if (a > b) {
        double swap = a;
        a = b;
        b = swap;
      }
      if (a > s0) s0 = a;
      if (b < s1) s1 = b;
    }
  }
  if (s0 > s1) return 0;
  *origin_out = rtcd_v3((float)p[0], (float)p[1], (float)p[2]);
  *along_out = rtcd_v3((float)d[0], (float)d[1], (float)d[2]);
  return 1;
}

/* A source item placed as what it is: a ray origin (rtcd_place_ray), an
 * edge (rtcd_place_edge), or a sphere's centre (its deepest-point item,
 * always a candidate of a job with candidates); the last two only when the
 * job tests them. Devices read the frame where it lies: a private copy of
 * its 168 bytes was read back before its stores had settled. */
RTCD_INLINE int rtcd_place_item(RTCD_GLOBAL const rtcd_frame* f, const rtcd_trace_params* p, rtcd_uint item,
                                rtcd_vec3 origin, rtcd_vec3 direction, rtcd_vec3* origin_out,
                                rtcd_vec3* direction_out) {
  if (item < p->first_edge) return rtcd_place_ray(f, origin, direction, origin_out, direction_out);
  if (!p->edges) return 0;
  if (p->source_radius > 0.0f) {
    *origin_out = rtcd_v3((float)f->translation[0], (float)f->translation[1], (float)f->translation[2]);
    *direction_out = rtcd_v3(0.0f, 0.0f, 0.0f);
    return 1;
  }
  return rtcd_place_edge(f, origin, direction, origin_out, direction_out);
}
#endif

#endif
