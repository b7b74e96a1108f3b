/* The predictive classification (section 2.1.3): what a ray's line status
 * means for its source vertex. A vertex whose line leaves the target ahead of
 * it is inside (a contact); one whose line leaves the target behind it,
 * within distanceExtension, is about to penetrate and stays tracked. */
#ifndef RTCD_KERNEL_CLASSIFY_H
#define RTCD_KERNEL_CLASSIFY_H

#include "types.h"

typedef enum {
  RTCD_RAY_DROPPED = 0,
  RTCD_RAY_PENETRATING = 1,
  RTCD_RAY_PREDICTIVE = 2
} rtcd_ray_kind;

RTCD_INLINE int rtcd_classify(int status, float t, int predictive, float distance_extension) {
  if (status == RTCD_LINE_HIT) return RTCD_RAY_PENETRATING;
  if (predictive && status == RTCD_LINE_BEHIND && -t <= distance_extension) return RTCD_RAY_PREDICTIVE;
  return RTCD_RAY_DROPPED;
}

#endif
