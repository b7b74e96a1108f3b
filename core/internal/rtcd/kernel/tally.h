/* A job's outcomes counted: the one rule by which the CPU executors
 * (settle_outcomes, into rtcd::RayTally) and the devices (rtcd_settle)
 * count them, so a step's counters do not depend on where it ran. */
#ifndef RTCD_KERNEL_TALLY_H
#define RTCD_KERNEL_TALLY_H

#include "classify.h"
#include "tracer.h"

/* The fields of rtcd::RayTally that outcomes count (edges_held is the
 * host's), and the job's kept outcomes (all but the dropped ones), of which
 * kept_origins are vertex rays (they come before the edges). */
typedef struct {
  rtcd_ulong contacts, predictive, kept, kept_origins;
  rtcd_ulong candidates, rays_full, rays_predictive, rays_iterative, walk_steps;
  rtcd_ulong nearest_queries, rays_retraced, rays_watched, fold_casts;
  rtcd_ulong edges_tested, edges_skipped, edge_rays, edge_contacts;
  rtcd_ulong walk_endings[RTCD_LINE_STATUS_COUNT];
} rtcd_tally;

RTCD_INLINE void rtcd_tally_clear(rtcd_tally* t) {
  int e;
  t->contacts = t->predictive = t->kept = t->kept_origins = 0;
  t->candidates = t->rays_full = t->rays_predictive = t->rays_iterative = t->walk_steps = 0;
  t->nearest_queries = t->rays_retraced = t->rays_watched = t->fold_casts = 0;
  t->edges_tested = t->edges_skipped = t->edge_rays = t->edge_contacts = 0;
  for (e = 0; e < RTCD_LINE_STATUS_COUNT; ++e) t->walk_endings[e] = 0;
}

RTCD_INLINE void rtcd_tally_add(rtcd_tally* t, const rtcd_tally* o) {
  int e;
  t->contacts += o->contacts;
  t->predictive += o->predictive;
  t->kept += o->kept;
  t->kept_origins += o->kept_origins;
  t->candidates += o->candidates;
  t->rays_full += o->rays_full;
  t->rays_predictive += o->rays_predictive;
  t->rays_iterative += o->rays_iterative;
  t->walk_steps += o->walk_steps;
  t->nearest_queries += o->nearest_queries;
  t->rays_retraced += o->rays_retraced;
  t->rays_watched += o->rays_watched;
  t->fold_casts += o->fold_casts;
  t->edges_tested += o->edges_tested;
  t->edges_skipped += o->edges_skipped;
  t->edge_rays += o->edge_rays;
  t->edge_contacts += o->edge_contacts;
  for (e = 0; e < RTCD_LINE_STATUS_COUNT; ++e) t->walk_endings[e] += o->walk_endings[e];
}

/* One outcome of a job (iterative: a walking one). */
RTCD_INLINE void rtcd_tally_count(rtcd_tally* t, const rtcd_outcome* o, int iterative) {
  t->contacts += o->kind == RTCD_RAY_PENETRATING;
  t->kept += o->kind != RTCD_RAY_DROPPED;
  t->kept_origins += o->kind != RTCD_RAY_DROPPED && !o->edge;
  t->rays_watched += o->kind == RTCD_RAY_WATCHED;
  if (o->edge) {
    ++t->edges_tested;
    /* A watched mesh edge that needs no ray: clear of the surface by more
     * than the pair has moved (its clearance rides in entry), or found
     * clear by its first walking step's nearest query. An edge against a
     * sphere or a box, tested in closed form, casts none either. */
    t->edges_skipped += o->edge == RTCD_ITEM_EDGE && o->edge_rays == 0 && (o->nearest_query || o->entry >= 0);
    t->edge_rays += o->edge_rays;
    t->nearest_queries += o->nearest_query;
    t->edge_contacts += o->kind == RTCD_RAY_PENETRATING;
    return;
  }
  ++t->candidates;
  t->predictive += o->kind == RTCD_RAY_PREDICTIVE;
  t->rays_predictive += o->predictive_cast;
  t->nearest_queries += o->nearest_query;
  t->rays_retraced += o->retraced;
  t->fold_casts += o->fold_cast;
  if (iterative) {
    ++t->rays_iterative;
    t->walk_steps += o->walk_steps;
    ++t->walk_endings[o->status];
  } else {
    ++t->rays_full;
  }
}

#endif
