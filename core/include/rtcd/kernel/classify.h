/* The predictive classification (section 2.1.3): what a ray's line status
 * means for its source vertex. A vertex whose line leaves the target ahead of
 * it is inside (a contact); one whose line leaves the target behind it,
 * within distanceExtension, is about to penetrate and stays tracked; one
 * near the target that reports neither is still walked each step (it may
 * enter sideways) until it moves away. */
#ifndef RTCD_KERNEL_CLASSIFY_H
#define RTCD_KERNEL_CLASSIFY_H

#include "types.h"

typedef enum {
  RTCD_RAY_DROPPED = 0,
  RTCD_RAY_PENETRATING = 1,
  RTCD_RAY_PREDICTIVE = 2,
  RTCD_RAY_WATCHED = 3 /* tracked, reports nothing this step */
} rtcd_ray_kind;

RTCD_INLINE int rtcd_classify(int status, float t, int predictive, float distance_extension) {
  if (status == RTCD_LINE_HIT) return RTCD_RAY_PENETRATING;
  if (predictive && status == RTCD_LINE_BEHIND && -t <= distance_extension) return RTCD_RAY_PREDICTIVE;
  return RTCD_RAY_DROPPED;
}

/* A walked ray that reports nothing stays watched unless its line now
 * leaves the target farther behind it than distanceExtension (moving away). */
RTCD_INLINE int rtcd_keep_watching(int status, float t, float distance_extension) {
  return !(status == RTCD_LINE_BEHIND && -t > distance_extension);
}

/* Whether a walked ray is inside. The exit walk found where the line leaves
 * the target (HIT: ahead of the vertex); the entry walk, from the face the
 * line entered through behind the vertex, must find that crossing still
 * behind it. Returns PENETRATING, or DROPPED when the entry is now ahead (the
 * vertex backed out), or -1 when the walks cannot tell: the ray is traced
 * again in full. An entering crossing behind the origin found by the exit
 * walk also means the vertex passed into the target there: traced again. */
RTCD_INLINE int rtcd_walked_inside(int exit_status, float exit_t, int entry_status, float entry_t) {
  if (exit_status == RTCD_LINE_FRONT && exit_t < 0.0f) return -1;
  if (exit_status != RTCD_LINE_HIT) return RTCD_RAY_DROPPED;
  if (entry_status != RTCD_LINE_FRONT) return -1;
  return entry_t <= 0.0f ? RTCD_RAY_PENETRATING : RTCD_RAY_DROPPED;
}

#endif
