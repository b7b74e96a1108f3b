/* Exact line intersection with the basic volumes, in their local frame
 * (centred at the origin, axis-aligned). The statuses read as for a mesh:
 * HIT when the origin is inside and the ray leaves at t >= 0. */
#ifndef RTCD_KERNEL_VOLUMES_H
#define RTCD_KERNEL_VOLUMES_H

#include "tracer.h"
#include "walk.h"

typedef struct {
  int status; /* rtcd_line_status: HIT, BEHIND, FRONT or MISS */
  int face;   /* box: exit face 0..5 = +x,-x,+y,-y,+z,-z; sphere, half-space: 0 */
  float t;    /* exit distance (entry distance when FRONT) */
} rtcd_volume_hit;

RTCD_INLINE rtcd_volume_hit rtcd_classify_span(float t_in, float t_out, int face) {
  rtcd_volume_hit h;
  h.face = face;
  if (t_out < 0.0f) {
    h.status = RTCD_LINE_BEHIND;
    h.t = t_out;
  } else if (t_in > 0.0f) {
    h.status = RTCD_LINE_FRONT;
    h.t = t_in;
  } else {
    h.status = RTCD_LINE_HIT;
    h.t = t_out;
  }
  return h;
}

/* direction must be unit length. */
RTCD_INLINE rtcd_volume_hit rtcd_sphere_line(rtcd_vec3 origin, rtcd_vec3 direction, float radius) {
  float b = rtcd_dot(origin, direction);
  float c = rtcd_dot(origin, origin) - radius * radius;
  float disc = b * b - c;
  if (disc < 0.0f) {
    rtcd_volume_hit miss;
    miss.status = RTCD_LINE_MISS;
    miss.face = 0;
    miss.t = 0.0f;
    return miss;
  }
  float s = RTCD_SQRT(disc);
  return rtcd_classify_span(-b - s, -b + s, 0);
}

RTCD_INLINE rtcd_volume_hit rtcd_box_line(rtcd_vec3 origin, rtcd_vec3 direction, rtcd_vec3 half_extents) {
  float t_in = -3.0e38f, t_out = 3.0e38f;
  int exit_face = 0;
  rtcd_volume_hit miss;
  miss.status = RTCD_LINE_MISS;
  miss.face = 0;
  miss.t = 0.0f;
  for (int k = 0; k < 3; ++k) {
    float o = rtcd_component(origin, k), d = rtcd_component(direction, k), h = rtcd_component(half_extents, k);
    if (d == 0.0f) {
      if (o < -h || o > h) return miss;
      continue;
    }
    float t_lo = (-h - o) / d, t_hi = (h - o) / d;
    float t_near = d > 0.0f ? t_lo : t_hi;
    float t_far = d > 0.0f ? t_hi : t_lo;
    if (t_near > t_in) t_in = t_near;
    if (t_far < t_out) {
      t_out = t_far;
      exit_face = 2 * k + (d > 0.0f ? 0 : 1);
    }
  }
  if (t_in > t_out) return miss;
  return rtcd_classify_span(t_in, t_out, exit_face);
}

/* The half-space z <= 0: a line leaves it only upward, through z = 0; a
 * line going down or level never leaves, and is a MISS even from inside. */
RTCD_INLINE rtcd_volume_hit rtcd_halfspace_line(rtcd_vec3 origin, rtcd_vec3 direction) {
  if (direction.z <= 0.0f) {
    rtcd_volume_hit miss;
    miss.status = RTCD_LINE_MISS;
    miss.face = 0;
    miss.t = 0.0f;
    return miss;
  }
  return rtcd_classify_span(-3.0e38f, -origin.z / direction.z, 0);
}

/* Where the line origin + s * along (along of any length) is inside a
 * sphere or a box: s in [*s_in, *s_out]. 0: the line misses it. */
RTCD_INLINE int rtcd_volume_span(int target_kind, float radius, rtcd_vec3 half_extents, rtcd_vec3 origin,
                                 rtcd_vec3 along, float* s_in, float* s_out) {
  if (target_kind == RTCD_TARGET_SPHERE) {
    float a = rtcd_dot(along, along), b = rtcd_dot(origin, along);
    float disc = b * b - a * (rtcd_dot(origin, origin) - radius * radius);
    float s;
    if (!(disc > 0.0f)) return 0;
    s = RTCD_SQRT(disc);
    *s_in = (-b - s) / a;
    *s_out = (-b + s) / a;
    return 1;
  } else {
    float lo = -3.0e38f, hi = 3.0e38f;
    int k;
    for (k = 0; k < 3; ++k) {
      float o = rtcd_component(origin, k), d = rtcd_component(along, k), h = rtcd_component(half_extents, k);
      float t0, t1;
      if (d == 0.0f) {
        if (o <= -h || o >= h) return 0;
        continue;
      }
      t0 = (-h - o) / d;
      t1 = (h - o) / d;
      if (t0 > t1) {
        float swap = t0;
        t0 = t1;
        t1 = swap;
      }
      if (t0 > lo) lo = t0;
      if (t1 < hi) hi = t1;
    }
    if (!(lo < hi)) return 0;
    *s_in = lo;
    *s_out = hi;
    return 1;
  }
}

/* How far a point lies inside a sphere or a box: the distance to its
 * surface, negative outside (box: the least room along an axis). */
RTCD_INLINE float rtcd_volume_room(int target_kind, float radius, rtcd_vec3 half_extents, rtcd_vec3 point) {
  if (target_kind == RTCD_TARGET_SPHERE) return radius - RTCD_SQRT(rtcd_dot(point, point));
  {
    float x = half_extents.x - RTCD_FABS(point.x), y = half_extents.y - RTCD_FABS(point.y);
    float z = half_extents.z - RTCD_FABS(point.z);
    return x < y ? (x < z ? x : z) : (y < z ? y : z);
  }
}

/* The face of a box nearest to a point inside it (0..5 = +x,-x,+y,-y,+z,-z;
 * ties to the lower id). */
RTCD_INLINE int rtcd_box_nearest_face(rtcd_vec3 point, rtcd_vec3 half_extents) {
  int face = 0, k;
  float best = 3.0e38f;
  for (k = 0; k < 3; ++k) {
    float c = rtcd_component(point, k), h = rtcd_component(half_extents, k);
    float up = h - c, down = h + c;
    if (up < best) {
      best = up;
      face = 2 * k;
    }
    if (down < best) {
      best = down;
      face = 2 * k + 1;
    }
  }
  return face;
}

#endif
