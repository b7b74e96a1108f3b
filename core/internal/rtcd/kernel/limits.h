/* A pair's limits for one step (displacement threshold, distance
 * extension, walk limit), by the rules of limits.hpp, from the two shapes'
 * scales, the pair's motion in the last step and the configuration's
 * settings. The pipeline derives them with it on the host, and a device
 * with it from a pair's motion (rtcd_prepare), so both have the same bits.
 * std::min and std::max's rules, spelled out: the first of equals. */
#ifndef RTCD_KERNEL_LIMITS_H
#define RTCD_KERNEL_LIMITS_H

#include "types.h"

#ifdef RTCD_HAS_DOUBLE
/* What the rules read of a shape (ShapeScale). */
typedef struct {
  double radius;    /* 0 for a half-space */
  double thickness; /* infinite for a half-space */
  double edge;      /* meshes: mean edge length; infinite otherwise */
  rtcd_uint triangles;
  rtcd_uint unused;
} rtcd_shape_scale;

/* rtcd_limit_settings::set: the limits the configuration sets. */
#define RTCD_LIMIT_THRESHOLD 1u
#define RTCD_LIMIT_EXTENSION 2u
#define RTCD_LIMIT_WALK 4u

/* The configuration's limits, where it sets them. */
typedef struct {
  double displacement_threshold;
  double distance_extension;
  rtcd_uint max_walk_steps;
  rtcd_uint set; /* RTCD_LIMIT_* */
} rtcd_limit_settings;

typedef struct {
  double displacement_threshold;
  double distance_extension;
  rtcd_uint max_walk_steps;
  rtcd_uint unused;
} rtcd_pair_limits;

RTCD_INLINE double rtcd_min_d(double a, double b) { return b < a ? b : a; }
RTCD_INLINE double rtcd_max_d(double a, double b) { return a < b ? b : a; }

/* The least extension the rules give a pair whose smaller shape has this
 * radius: a resting pair's (no motion). */
RTCD_INLINE double rtcd_resting_extension(double radius) { return radius / 10.0; }

/* The rules of limits.hpp; `motion` is m. */
RTCD_INLINE rtcd_pair_limits rtcd_derive_limits(const rtcd_limit_settings* c, const rtcd_shape_scale* a,
                                                const rtcd_shape_scale* b, double motion) {
  rtcd_pair_limits l;
  const double size = a->radius <= 0.0 ? b->radius : b->radius <= 0.0 ? a->radius : rtcd_min_d(a->radius, b->radius);
  const double thickness = rtcd_min_d(rtcd_min_d(a->thickness, b->thickness), 2.0 * size);
  l.distance_extension = (c->set & RTCD_LIMIT_EXTENSION)
                             ? c->distance_extension
                             : rtcd_max_d(rtcd_resting_extension(size), rtcd_min_d(2.0 * motion, size));
  l.displacement_threshold = (c->set & RTCD_LIMIT_THRESHOLD)
                                 ? c->displacement_threshold
                                 : rtcd_min_d(l.distance_extension / 2.0, thickness / 4.0);
  if (!(c->set & RTCD_LIMIT_EXTENSION)) l.distance_extension = rtcd_max_d(l.distance_extension, l.displacement_threshold);
  if (c->set & RTCD_LIMIT_WALK) {
    l.max_walk_steps = c->max_walk_steps;
  } else {
    const double edge = rtcd_min_d(a->edge, b->edge);
    const double reach = 4.0 * rtcd_max_d(2.0 * motion, l.displacement_threshold);
    /* edge - edge is 0 only for a finite edge */
    const double steps = edge - edge == 0.0 && edge > 0.0 ? ceil(reach / edge) : 0.0;
    const double most = rtcd_max_d(32.0, (double)(a->triangles < b->triangles ? b->triangles : a->triangles));
    const double highest = rtcd_min_d(most, 1000000.0);
    l.max_walk_steps = (rtcd_uint)(steps < 32.0 ? 32.0 : highest < steps ? highest : steps);
  }
  l.unused = 0;
  return l;
}
#endif

#endif
