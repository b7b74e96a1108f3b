/* A job's setup: what the host decides for one pair-direction (its bodies
 * and shapes, limits, motion, mode, whether it tests edges) and the one
 * function that makes its per-ray parameters from it, run by the CPU
 * executor and by a device (the OpenCL executor's rtcd_prepare) alike, so
 * a device is sent the setup and makes the same bits. */
#ifndef RTCD_KERNEL_JOB_H
#define RTCD_KERNEL_JOB_H

#include "limits.h"
#include "tracer.h"

/* rtcd_job_setup::flags */
#define RTCD_JOB_ITERATIVE 1u /* walks last step's rays */
#define RTCD_JOB_EDGES 2u     /* this direction tests its source's edges */

/* The configuration's switches a job's parameters read, as one word. */
#define RTCD_CONFIG_PREDICTIVE 1u /* Config::predictive */
#define RTCD_CONFIG_WATCH 2u      /* predictive rays on and not Mode::full: vertices near the target are watched */
#define RTCD_CONFIG_VERIFY 4u     /* Config::verify_walks */
#define RTCD_CONFIG_EDGES 8u      /* Config::edge_contacts */
#define RTCD_CONFIG_NEAREST 16u   /* Config::nearest_surface */
#define RTCD_CONFIG_AUTOMATIC 32u /* Mode::automatic: vertices are watched within the displacement threshold */

/* What a shape brings to the parameters of the jobs it is in. */
typedef struct {
  rtcd_int kind;        /* RTCD_TARGET_* */
  rtcd_int convex;      /* a convex mesh: a walk cannot fold in it */
  rtcd_uint first_edge; /* its items from here on are edges */
  float sphere_radius;  /* a sphere: its radius; 0 otherwise */
} rtcd_shape_traits;

/* The least float >= x and the greatest float <= x: a float lies in a
 * double interval exactly when it lies between these bounds of its ends. */
RTCD_INLINE float rtcd_float_at_least(double x) {
  float f = (float)x;
  return (double)f < x ? RTCD_NEXTAFTER(f, INFINITY) : f;
}
RTCD_INLINE float rtcd_float_at_most(double x) {
  float f = (float)x;
  return (double)f > x ? RTCD_NEXTAFTER(f, -INFINITY) : f;
}

/* RTCD_JOB_EDGES of a pair setup's direction d. */
#define RTCD_PAIR_EDGES(d) (RTCD_JOB_EDGES << (d))
/* The pair's motion is equation 2.1 from its bodies' poses of the last
 * step to this step's (rtcd_pair_motion); else it is 0. */
#define RTCD_PAIR_MOTION 8u

/* One pair as the host decided it, both directions in one: direction 0
 * casts the first body's rays against the second, direction 1 the
 * second's against the first. The directions share the motion (derived on
 * the device from the poses: rtcd_pair_motion), the limits derived from it
 * and the mode, and their items follow one another, after the pair
 * before's (a device scans the counts: rtcd_pair_list). The bodies'
 * shapes are the device's already. 32 bytes. */
typedef struct {
  rtcd_uint bodies[2];
  rtcd_uint flags; /* RTCD_JOB_ITERATIVE, RTCD_PAIR_EDGES(d), RTCD_PAIR_MOTION */
  float moved;     /* iterative pairs: since the pair's full step (equation 2.1), rounded up */
  rtcd_uint item_count[2];
  rtcd_uint first[2]; /* iterative: where its tracked rays are; full: its near leaves */
} rtcd_pair_setup;

#ifdef RTCD_HAS_DOUBLE
/* One pair-direction as the host decided it. 64 bytes. */
typedef struct {
  double extension; /* PairLimits::distance_extension */
  double reach;     /* PairLimits::watch_reach: how far from the target a vertex is watched */
  float moved;      /* iterative jobs: the pair's motion since its full step (equation 2.1), rounded up */
  rtcd_uint source_body;
  rtcd_uint target_body;
  rtcd_uint source; /* shapes */
  rtcd_uint target;
  rtcd_uint max_walk_steps;
  rtcd_uint flags; /* RTCD_JOB_* */
  rtcd_uint first_item;
  rtcd_uint item_count;
  rtcd_uint first_tracked; /* iterative jobs: where its tracked rays are */
  rtcd_uint first_near;    /* full jobs: where its near leaves are */
  rtcd_uint unused;        /* 0: no padding, so two setups compare bytewise */
} rtcd_job_setup;

/* Direction d's setup, with the pair's limits derived from its motion in
 * the last step, the settings and its bodies' shapes' scales (bodies[0]'s
 * shape and scale, then bodies[1]'s: the rules are symmetric);
 * `first_item` is direction 0's. */
RTCD_INLINE rtcd_job_setup rtcd_direction_setup(const rtcd_pair_setup* p, rtcd_uint d, rtcd_uint first_item,
                                                double motion, rtcd_uint config,
                                                const rtcd_limit_settings* settings, rtcd_uint shape_0,
                                                rtcd_uint shape_1, const rtcd_shape_scale* scale_0,
                                                const rtcd_shape_scale* scale_1) {
  rtcd_job_setup s;
  const int iterative = (p->flags & RTCD_JOB_ITERATIVE) != 0;
  const rtcd_pair_limits limits = rtcd_derive_limits(settings, scale_0, scale_1, motion);
  s.extension = limits.distance_extension;
  s.reach = (config & RTCD_CONFIG_AUTOMATIC) ? limits.displacement_threshold : limits.distance_extension;
  s.moved = p->moved;
  s.source_body = p->bodies[d];
  s.target_body = p->bodies[1 - d];
  s.source = d ? shape_1 : shape_0;
  s.target = d ? shape_0 : shape_1;
  s.max_walk_steps = limits.max_walk_steps;
  s.flags = (p->flags & RTCD_JOB_ITERATIVE) | ((p->flags & RTCD_PAIR_EDGES(d)) ? RTCD_JOB_EDGES : 0u);
  s.first_item = first_item + (d ? p->item_count[0] : 0u);
  s.item_count = p->item_count[d];
  s.first_tracked = iterative ? p->first[d] : 0u;
  s.first_near = iterative ? 0u : p->first[d];
  s.unused = 0;
  return s;
}

/* The job's per-ray parameters. Watching serves only later walks, which
 * full mode never makes; it belongs to the predictive logic and is off
 * with it. A convex target cannot fold between a ray's entry and exit
 * faces. A half-space needs no edge test: a body crossing its plane has an
 * origin below it. A sphere has no edges: its deepest point is tested
 * against spheres and boxes only. */
RTCD_INLINE rtcd_trace_params rtcd_make_params(rtcd_uint config, const rtcd_job_setup* s,
                                               const rtcd_shape_traits* source, const rtcd_shape_traits* target,
                                               const rtcd_box* target_bounds) {
  rtcd_trace_params p;
  int mesh = target->kind == RTCD_TARGET_MESH;
  p.watch_lo = rtcd_v3(rtcd_float_at_least(target_bounds->lo[0] - s->reach),
                       rtcd_float_at_least(target_bounds->lo[1] - s->reach),
                       rtcd_float_at_least(target_bounds->lo[2] - s->reach));
  p.watch_hi = rtcd_v3(rtcd_float_at_most(target_bounds->hi[0] + s->reach),
                       rtcd_float_at_most(target_bounds->hi[1] + s->reach),
                       rtcd_float_at_most(target_bounds->hi[2] + s->reach));
  p.extension = (float)s->extension;
  p.reach = (float)s->reach;
  p.max_walk_steps = s->max_walk_steps;
  p.predictive = (config & RTCD_CONFIG_PREDICTIVE) != 0;
  p.watch = (config & RTCD_CONFIG_WATCH) != 0;
  p.verify = (config & RTCD_CONFIG_VERIFY) != 0 && !(mesh && target->convex);
  p.iterative = (s->flags & RTCD_JOB_ITERATIVE) != 0;
  p.moved = s->moved;
  p.first_edge = source->first_edge;
  p.source_radius = source->sphere_radius;
  p.edges = (s->flags & RTCD_JOB_EDGES) != 0 && (config & RTCD_CONFIG_EDGES) != 0 &&
            target->kind != RTCD_TARGET_HALFSPACE && !(p.source_radius > 0.0f && mesh);
  p.nearest_surface = (config & RTCD_CONFIG_NEAREST) != 0 && mesh;
  return p;
}
#endif

#endif
