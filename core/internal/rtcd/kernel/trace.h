/* One candidate ray's work in a step, written once for every executor: the
 * full trace (inward ray, predictive ray, watched vertices), the walks of an
 * iterative step with their re-trace, and the exact line tests of volumes.
 *
 * The includer supplies the mesh tracer before including this header:
 *   typedef ... rtcd_tracer;
 *   rtcd_hit rtcd_tracer_first_hit(const rtcd_tracer*, const rtcd_ray*, float t_max);
 *   rtcd_int rtcd_tracer_nearest(const rtcd_tracer*, rtcd_vec3 point, float radius, float enough);
 *     (the nearest triangle within radius, or -1; a tracer may stop at any
 *     triangle within `enough` of the point instead, 0: never)
 *   rtcd_walk_result rtcd_tracer_walk(const rtcd_tracer*, const rtcd_ray*, rtcd_int start, rtcd_uint max_steps);
 *   int rtcd_tracer_leaves(const rtcd_tracer*, rtcd_int triangle, rtcd_vec3 direction);
 *     (direction . the triangle's unit normal > 0)
 *   int rtcd_tracer_fold_free(const rtcd_tracer*, rtcd_int face, rtcd_vec3 origin, rtcd_vec3 toward, float reach);
 *     (rtcd_fold_free of fold.h over the mesh's FoldGuard)
 *   float rtcd_tracer_distance2(const rtcd_tracer*, rtcd_int triangle, rtcd_vec3 point);
 *     (rtcd_point_triangle_distance2 of nearest.h)
 * The CPU executor backs it with a MeshTracer, the device with its own
 * brute-force or BVH traversal over buffers. */
#ifndef RTCD_KERNEL_TRACE_H
#define RTCD_KERNEL_TRACE_H

#include "classify.h"
#include "nearest.h"
#include "tracer.h"
#include "volumes.h"
#include "walk.h"

/* A penetrating ray's way out (Config::nearest_surface): the target's
 * triangle nearest the vertex, searched no farther than the face the ray
 * leaves through (most often the nearest itself). The ray proves the
 * vertex is inside; how deep and which way out is the nearest surface's (a
 * thin tube's inward ray crosses the tube and leaves a blob far beyond
 * it). The host measures depth and direction to that triangle in double;
 * none found (rounding): the exit face. */
RTCD_INLINE void rtcd_nearest_surface(const rtcd_tracer* tracer, const rtcd_trace_params* p, const rtcd_candidate* c,
                                      rtcd_outcome* o) {
  float exit;
  if (!p->nearest_surface || o->kind != RTCD_RAY_PENETRATING) return;
  exit = RTCD_SQRT(rtcd_tracer_distance2(tracer, o->triangle, c->origin));
  o->nearest_query = 1;
  o->nearest = rtcd_tracer_nearest(tracer, c->origin, exit * 1.0001f, 0.0f);
  if (o->nearest < 0) o->nearest = o->triangle;
}

/* Full tracing of one mesh ray: the inward ray; if it does not leave the
 * target, the predictive ray; if neither meets it and the vertex is within
 * reach of the target's box, it is watched. What serves only later walks
 * (the entry face of a penetrating ray, a watched vertex's nearest
 * triangle) is found only when `walking` (a walk's re-trace), so full steps
 * of pairs traced in full again cost no more. Sets kind, triangle and t;
 * may set entry, predictive_cast and nearest_query. */
RTCD_INLINE void rtcd_full_trace(const rtcd_tracer* tracer, const rtcd_trace_params* p, const rtcd_candidate* c,
                                 int walking, rtcd_outcome* o) {
  rtcd_ray inward = rtcd_make_ray(c->origin, c->direction);
  rtcd_ray outward = rtcd_make_ray(c->origin, rtcd_neg(c->direction));
  rtcd_hit in, out;
  rtcd_int near;
  o->kind = RTCD_RAY_DROPPED;
  o->triangle = -1;
  o->t = 0.0f;
  /* Inward ray: a first hit leaving the target means the origin is inside. */
  in = rtcd_tracer_first_hit(tracer, &inward, 3.0e38f);
  if (in.triangle >= 0 && rtcd_tracer_leaves(tracer, in.triangle, c->direction)) {
    o->kind = RTCD_RAY_PENETRATING;
    o->triangle = in.triangle;
    o->t = in.t;
    /* Where the line entered, behind the vertex: the next walks check the
     * vertex is still past it. */
    if (walking) {
      rtcd_hit back = rtcd_tracer_first_hit(tracer, &outward, 3.0e38f);
      if (back.triangle >= 0 && !rtcd_tracer_leaves(tracer, back.triangle, c->direction)) o->entry = back.triangle;
    }
    rtcd_nearest_surface(tracer, p, c, o);
    return;
  }
  if (!p->predictive) return;
  /* Predictive ray: outward, no further than distance_extension. */
  out = rtcd_tracer_first_hit(tracer, &outward, p->extension);
  o->predictive_cast = 1;
  if (out.triangle >= 0 && rtcd_tracer_leaves(tracer, out.triangle, c->direction)) {
    o->kind = RTCD_RAY_PREDICTIVE;
    o->triangle = out.triangle;
    o->t = -out.t;
    return;
  }
  if (!p->watch || !rtcd_inside_box(c->origin, p->watch_lo, p->watch_hi)) return;
  if (!walking) {
    o->kind = RTCD_RAY_WATCHED; /* triangle -1: looked up if the pair walks */
    return;
  }
  o->nearest_query = 1;
  near = rtcd_tracer_nearest(tracer, c->origin, p->reach, 0.0f);
  if (near >= 0) {
    o->kind = RTCD_RAY_WATCHED;
    o->triangle = near;
  }
}

/* An iterative step's mesh ray: the exit walk from the tracked triangle (a
 * watched vertex first looks up its nearest triangle), the entry walk for a
 * hit, rtcd_walked_kind's verdict, and the full re-trace it may ask for. */
RTCD_INLINE void rtcd_walk_trace(const rtcd_tracer* tracer, const rtcd_trace_params* p, const rtcd_candidate* c,
                                 rtcd_outcome* o) {
  rtcd_ray ray = rtcd_make_ray(c->origin, c->direction);
  rtcd_int start = c->start;
  rtcd_walk_result exit_walk, entry_walk;
  int kind, located;
  if (start < 0) {
    /* Watched since the full step, its nearest triangle not looked up yet:
     * done now that the pair walks. */
    o->nearest_query = 1;
    start = rtcd_tracer_nearest(tracer, c->origin, p->reach, 0.0f);
    if (start < 0) return; /* dropped: nothing within reach */
  }
  exit_walk = rtcd_tracer_walk(tracer, &ray, start, p->max_walk_steps);
  o->walk_steps += exit_walk.steps;
  o->status = (rtcd_uchar)exit_walk.status;
  entry_walk.status = RTCD_LINE_MISS;
  entry_walk.triangle = -1;
  entry_walk.t = 0.0f;
  entry_walk.steps = 0;
  if (exit_walk.status == RTCD_LINE_HIT && c->entry >= 0) {
    entry_walk = rtcd_tracer_walk(tracer, &ray, c->entry, p->max_walk_steps);
    o->walk_steps += entry_walk.steps;
  }
  /* near = 0: a mesh's box is a weak bound on the distance to its surface
   * (a concave mesh's box holds most vertices near it), and keeping every
   * vertex in it walking cost 60% more per steady step (rtcd_bench
   * iterative/64) for no missed ray in the validation. */
  kind = rtcd_walked_kind(exit_walk.status, exit_walk.t, entry_walk.status, entry_walk.t, p->predictive, p->watch, 0,
                          p->extension);
  /* The walks see the crossings they track, not a fold of the target
   * between them: a vertex that moved out into a gap between its entry and
   * exit faces would still read as inside (and a fold ahead of a vertex
   * inside makes its depth stale). A vertex between the two faces is
   * outside only if the line crosses the surface on both sides of it, so
   * one cast toward the nearer face, no farther, catches it; any other face
   * there sends the ray to a full trace (which also corrects a stale depth
   * when the fold is ahead and the exit face is the nearer). */
  if (kind == RTCD_RAY_PENETRATING && p->verify) {
    int ahead = exit_walk.t <= -entry_walk.t;
    float reach = ahead ? exit_walk.t : -entry_walk.t;
    rtcd_int face = ahead ? exit_walk.triangle : entry_walk.triangle;
    rtcd_vec3 toward = ahead ? c->direction : rtcd_neg(c->direction);
    /* Most contacts lie where the face's neighbours and clearance already
     * rule a fold out (fold.h); elsewhere a ray looks. */
    o->fold_cast = !rtcd_tracer_fold_free(tracer, face, c->origin, toward, reach);
    if (o->fold_cast) {
      rtcd_ray cast = rtcd_make_ray(c->origin, toward);
      rtcd_hit between = rtcd_tracer_first_hit(tracer, &cast, reach);
      if (between.triangle >= 0 && between.triangle != face) kind = -1;
    }
  }
  if (kind < 0) {
    o->retraced = 1;
    rtcd_full_trace(tracer, p, c, 1, o);
    return;
  }
  located = exit_walk.status == RTCD_LINE_HIT || exit_walk.status == RTCD_LINE_BEHIND ||
            exit_walk.status == RTCD_LINE_FRONT;
  o->kind = (rtcd_uchar)kind;
  o->triangle = located ? exit_walk.triangle : start;
  o->t = exit_walk.t;
  if (kind == RTCD_RAY_PENETRATING) o->entry = entry_walk.triangle;
  rtcd_nearest_surface(tracer, p, c, o);
}

/* A ray against a volume: the line test is exact, in both modes; a
 * candidate neither inside nor about to enter is watched while it stays
 * near, in full steps as in iterative ones. */
RTCD_INLINE void rtcd_volume_trace(int target_kind, float radius, rtcd_vec3 half_extents,
                                   const rtcd_trace_params* p, const rtcd_candidate* c, rtcd_outcome* o) {
  rtcd_volume_hit h = target_kind == RTCD_TARGET_SPHERE ? rtcd_sphere_line(c->origin, c->direction, radius)
                      : target_kind == RTCD_TARGET_BOX  ? rtcd_box_line(c->origin, c->direction, half_extents)
                                                        : rtcd_halfspace_line(c->origin, c->direction);
  o->status = (rtcd_uchar)h.status;
  o->kind = (rtcd_uchar)rtcd_line_kind(h.status, h.t, p->predictive, p->watch,
                                       rtcd_inside_box(c->origin, p->watch_lo, p->watch_hi), p->extension);
  o->t = h.t;
  o->triangle = h.face;
}

/* Touching is not crossing: a contact point closer to the surface than
 * this fraction of its edge's length (or of a sphere's radius), about 16
 * float roundings of a coordinate, is on it. */
#define RTCD_TOUCHING 1.0e-6f

/* An edge that makes no contact stays watched, in walking modes, while its
 * segment's box is within the watch reach of the target's box: it is
 * tested again in walking steps (against a mesh, once the pair has moved
 * its clearance), so a crossing is found in the step it begins. */
RTCD_INLINE void rtcd_watch_edge(const rtcd_trace_params* p, const rtcd_candidate* c, rtcd_outcome* o) {
  rtcd_vec3 end = rtcd_add(c->origin, c->direction);
  if (p->watch && !(c->origin.x > p->watch_hi.x && end.x > p->watch_hi.x) &&
      !(c->origin.y > p->watch_hi.y && end.y > p->watch_hi.y) &&
      !(c->origin.z > p->watch_hi.z && end.z > p->watch_hi.z) &&
      !(c->origin.x < p->watch_lo.x && end.x < p->watch_lo.x) &&
      !(c->origin.y < p->watch_lo.y && end.y < p->watch_lo.y) && !(c->origin.z < p->watch_lo.z && end.z < p->watch_lo.z))
    o->kind = RTCD_RAY_WATCHED;
}

/* A watched edge's clearance: how far the pair may move before the edge can
 * cross the target's surface. Found in the first walking step after a full
 * step (full steps of pairs traced in full again pay nothing for it): the
 * distance from the edge's middle to its nearest triangle less half the
 * edge's length, a bound on every point of the edge. It is kept, less the
 * motion already made (moved since the full step), in the outcome's entry
 * field: a later step whose motion since the full step stays below it
 * cannot move any point of the edge that far from where it was measured
 * (equation 2.1 bounds both motions). Returns the clearance, or -1 when no
 * surface is within reach: the pair is traced in full before it moves that
 * far, so the edge is dropped. */
RTCD_INLINE float rtcd_edge_clearance(const rtcd_tracer* tracer, const rtcd_trace_params* p, const rtcd_candidate* c,
                                      rtcd_outcome* o) {
  float half_length = 0.5f * RTCD_SQRT(rtcd_dot(c->direction, c->direction)), clearance;
  rtcd_vec3 middle = rtcd_add(c->origin, rtcd_scale(c->direction, 0.5f));
  rtcd_int near;
  o->nearest_query = 1;
  /* Any triangle within half the length makes the clearance 0: the search
   * may stop there. */
  near = rtcd_tracer_nearest(tracer, middle, half_length + p->reach + p->moved, half_length);
  if (near < 0) return -1.0f;
  clearance = RTCD_SQRT(rtcd_tracer_distance2(tracer, near, middle)) - half_length;
  return clearance > 0.0f ? clearance : 0.0f;
}

/* Whether the point origin + m * along lies inside the target: its line
 * back toward the edge's first end leaves the target first. Sets *back to
 * that first hit. */
RTCD_INLINE int rtcd_edge_point_inside(const rtcd_tracer* tracer, const rtcd_candidate* c, float m, rtcd_hit* back,
                                       rtcd_outcome* o) {
  rtcd_vec3 point = rtcd_add(c->origin, rtcd_scale(c->direction, m));
  rtcd_ray ray = rtcd_make_ray(point, rtcd_neg(c->direction));
  *back = rtcd_tracer_first_hit(tracer, &ray, m);
  ++o->edge_rays;
  return back->triangle >= 0 && back->t > 0.0f && rtcd_tracer_leaves(tracer, back->triangle, rtcd_neg(c->direction));
}

/* One edge of the source against a mesh: a crossing with neither end
 * inside (an end inside is its own ray's contact). The edge's line is
 * traced from each end toward the other, no farther: both first hits must
 * enter the target, at fractions a and b of the edge from its first end.
 * The contact lies at m, the middle of [a, b], when that point is inside
 * (a ray from it back toward the first end leaves the target first);
 * otherwise the edge crosses the target in several pieces, and the middle
 * of the first piece is tried the same way. Its face is the triangle
 * nearest to that point (the host measures depth and direction to it in
 * double); t is m. Deterministic: every decision is a first hit or a
 * nearest triangle under the tie rules of tracer.h. */
RTCD_INLINE void rtcd_edge_trace(const rtcd_tracer* tracer, const rtcd_trace_params* p, const rtcd_candidate* c,
                                 rtcd_outcome* o) {
  rtcd_ray forward, backward; /* made only for the tests that trace them */
  rtcd_hit first, last, back;
  rtcd_vec3 point;
  float a, b, m, length, tolerance;
  o->edge = RTCD_ITEM_EDGE;
  o->kind = RTCD_RAY_DROPPED;
  o->entry = c->entry;
  if (p->iterative) {
    if (c->entry < 0 && p->moved > 0.5f * p->reach) {
      /* Moved more than half the reach already: the pair is soon traced in
       * full again, and a clearance would keep little; tested by rays. */
      o->entry = rtcd_float_bits(0.0f);
    } else if (c->entry < 0) {
      /* Its clearance not known yet: a segment clear of the surface does
       * not cross it now, and needs no ray. */
      float clearance = rtcd_edge_clearance(tracer, p, c, o);
      if (clearance < 0.0f) return;
      o->entry = rtcd_float_bits(clearance > p->moved ? clearance - p->moved : 0.0f);
      if (clearance > 0.0f) {
        o->kind = RTCD_RAY_WATCHED;
        return;
      }
    } else if (rtcd_bits_float(c->entry) > p->moved) {
      /* Still farther from the surface than the pair has moved. */
      o->kind = RTCD_RAY_WATCHED;
      return;
    }
  }
  forward = rtcd_make_ray(c->origin, c->direction);
  first = rtcd_tracer_first_hit(tracer, &forward, 1.0f);
  o->edge_rays = 1;
  if (first.triangle < 0 || rtcd_tracer_leaves(tracer, first.triangle, c->direction)) {
    rtcd_watch_edge(p, c, o);
    return;
  }
  backward = rtcd_make_ray(rtcd_add(c->origin, c->direction), rtcd_neg(c->direction));
  last = rtcd_tracer_first_hit(tracer, &backward, 1.0f);
  o->edge_rays = 2;
  if (last.triangle < 0 || rtcd_tracer_leaves(tracer, last.triangle, rtcd_neg(c->direction))) {
    rtcd_watch_edge(p, c, o);
    return;
  }
  a = first.t;
  b = 1.0f - last.t;
  m = 0.5f * (a + b);
  if (!(a < b) || !rtcd_edge_point_inside(tracer, c, m, &back, o)) {
    /* Touching (no span), or the middle lies in a gap between pieces: the
     * first piece ends where the ray from the middle met the surface. */
    if (!(a < b) || back.triangle < 0) {
      rtcd_watch_edge(p, c, o);
      return;
    }
    b = m - back.t;
    m = 0.5f * (a + b);
    if (!(a < b) || !rtcd_edge_point_inside(tracer, c, m, &back, o)) {
      rtcd_watch_edge(p, c, o);
      return;
    }
  }
  /* The surface is within (m - a) of the point: its entry lies there. */
  length = RTCD_SQRT(rtcd_dot(c->direction, c->direction));
  point = rtcd_add(c->origin, rtcd_scale(c->direction, m));
  o->triangle = rtcd_tracer_nearest(tracer, point, (b - a) * length, 0.0f);
  if (o->triangle < 0) o->triangle = first.triangle;
  tolerance = RTCD_TOUCHING * length;
  if (!(rtcd_tracer_distance2(tracer, o->triangle, point) > tolerance * tolerance)) {
    rtcd_watch_edge(p, c, o);
    return;
  }
  o->kind = RTCD_RAY_PENETRATING;
  o->t = m;
}

/* One edge of the source against a sphere or a box: the exact span of its
 * line inside the volume, [a, b] in fractions of the edge; a crossing when
 * both ends are outside and the span lies between them. The contact lies
 * at the span's middle, its face the nearest (box: the face with the least
 * room; sphere: 0). A half-space has no edge test: a body crossing its
 * plane has a ray origin below it. */
RTCD_INLINE void rtcd_edge_volume_trace(int target_kind, float radius, rtcd_vec3 half_extents,
                                        const rtcd_trace_params* p, const rtcd_candidate* c, rtcd_outcome* o) {
  float a = 0.0f, b = 0.0f, m;
  rtcd_vec3 point;
  o->edge = RTCD_ITEM_EDGE;
  o->kind = RTCD_RAY_DROPPED;
  if (target_kind == RTCD_TARGET_HALFSPACE) return;
  if (!rtcd_volume_span(target_kind, radius, half_extents, c->origin, c->direction, &a, &b) || !(a > 0.0f) ||
      !(b < 1.0f)) {
    rtcd_watch_edge(p, c, o);
    return;
  }
  m = 0.5f * (a + b);
  point = rtcd_add(c->origin, rtcd_scale(c->direction, m));
  if (!(rtcd_volume_room(target_kind, radius, half_extents, point) >
        RTCD_TOUCHING * RTCD_SQRT(rtcd_dot(c->direction, c->direction)))) {
    rtcd_watch_edge(p, c, o);
    return;
  }
  o->kind = RTCD_RAY_PENETRATING;
  o->t = m;
  o->triangle = target_kind == RTCD_TARGET_BOX ? rtcd_box_nearest_face(point, half_extents) : 0;
}

/* A sphere source against a sphere or a box: the closed-form test that no
 * sampling replaces (a cap can push into a face between its sample
 * points). The sphere's deepest point toward the target (toward a sphere's
 * centre; toward a box's nearest point to the centre) is a contact when it
 * lies inside the target; its face is the nearest (sphere: 0). A centre
 * inside the box is left to the sample points and the box's corners and
 * edges, which then cross the sphere; the item stays watched in walking
 * modes, so it is tested every step. */
RTCD_INLINE void rtcd_sphere_trace(int target_kind, float radius, rtcd_vec3 half_extents, const rtcd_trace_params* p,
                                   const rtcd_candidate* c, rtcd_outcome* o) {
  rtcd_vec3 centre = c->origin, toward, point;
  float d;
  o->edge = RTCD_ITEM_SPHERE;
  o->kind = p->watch ? RTCD_RAY_WATCHED : RTCD_RAY_DROPPED;
  if (target_kind == RTCD_TARGET_SPHERE) {
    toward = rtcd_neg(centre);
  } else if (target_kind == RTCD_TARGET_BOX) {
    rtcd_vec3 q = rtcd_v3(centre.x < -half_extents.x ? -half_extents.x : (centre.x > half_extents.x ? half_extents.x : centre.x),
                          centre.y < -half_extents.y ? -half_extents.y : (centre.y > half_extents.y ? half_extents.y : centre.y),
                          centre.z < -half_extents.z ? -half_extents.z : (centre.z > half_extents.z ? half_extents.z : centre.z));
    toward = rtcd_sub(q, centre);
  } else {
    o->kind = RTCD_RAY_DROPPED;
    return;
  }
  d = RTCD_SQRT(rtcd_dot(toward, toward));
  if (!(d > 0.0f)) return;
  point = rtcd_add(centre, rtcd_scale(toward, p->source_radius / d));
  if (!(rtcd_volume_room(target_kind, radius, half_extents, point) > RTCD_TOUCHING * p->source_radius)) return;
  o->kind = RTCD_RAY_PENETRATING;
  o->t = 0.0f;
  o->triangle = target_kind == RTCD_TARGET_BOX ? rtcd_box_nearest_face(point, half_extents) : 0;
}

#endif
