/* The predictive classification (section 2.1.3): what a ray's line status
 * means for its source vertex. A vertex whose line leaves the target ahead of
 * it is inside (a contact); one whose line leaves the target behind it,
 * within distanceExtension, is about to penetrate and stays tracked; one
 * near the target that reports neither is watched: still walked each step
 * (it may enter sideways) until it moves away. */
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

/* A line status as a tracked ray's kind: rtcd_classify, except that a ray
 * that reports nothing stays watched (when `watch`: only walks use it) while
 * the vertex is `near` (within the watch reach of the target's box) or its
 * line does not leave the target farther behind it than distanceExtension:
 * a vertex is dropped only once it is both out of reach and moving away. */
RTCD_INLINE int rtcd_line_kind(int status, float t, int predictive, int watch, int near, float distance_extension) {
  int kind = rtcd_classify(status, t, predictive, distance_extension);
  if (kind == RTCD_RAY_DROPPED && watch && (near || !(status == RTCD_LINE_BEHIND && -t > distance_extension)))
    kind = RTCD_RAY_WATCHED;
  return kind;
}

/* The kind of a walked ray. The exit walk found where the line leaves the
 * target (HIT: ahead of the vertex); the entry walk, from the face the line
 * entered through behind the vertex, must find that crossing still behind
 * it, or the vertex backed out (the target is ahead: watched). -1 when the
 * walks cannot tell and the ray is traced again in full: a hit whose entry
 * walk located no entering crossing (or had no entry face to start from),
 * or an entering crossing behind the origin found by the exit walk (the
 * vertex passed into the target there). */
RTCD_INLINE int rtcd_walked_kind(int exit_status, float exit_t, int entry_status, float entry_t, int predictive,
                                 int watch, int near, float distance_extension) {
  if (exit_status == RTCD_LINE_FRONT && exit_t < 0.0f) return -1;
  if (exit_status != RTCD_LINE_HIT)
    return rtcd_line_kind(exit_status, exit_t, predictive, watch, near, distance_extension);
  if (entry_status != RTCD_LINE_FRONT) return -1;
  if (entry_t <= 0.0f) return RTCD_RAY_PENETRATING;
  return watch ? RTCD_RAY_WATCHED : RTCD_RAY_DROPPED;
}

#endif
