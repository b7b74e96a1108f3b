/* The buffers the OpenCL host code and kernels.cl share, in the C subset
 * that is also OpenCL C 1.2 (one definition for both sides). */
#ifndef RTCD_OPENCL_DEVICE_TYPES_H
#define RTCD_OPENCL_DEVICE_TYPES_H

#include "rtcd/kernel/bvh.h"
#include "rtcd/kernel/fold.h"
#include "rtcd/kernel/job.h"
#include "rtcd/kernel/near.h"
#include "rtcd/kernel/tally.h"
#include "rtcd/kernel/tracer.h"

/* A registered shape: where its data lies in the concatenated buffers. */
typedef struct {
  rtcd_int kind; /* RTCD_TARGET_* of trace.h */
  rtcd_uint first_vertex;
  rtcd_uint first_triangle; /* triangles, neighbours, zero-area flags and normals */
  rtcd_uint triangle_count;
  rtcd_uint first_node; /* BVH nodes */
  rtcd_uint node_count;
  rtcd_uint first_wide;      /* the BVH's wide nodes */
  rtcd_uint first_primitive; /* the BVH's triangle list */
  rtcd_uint first_source;    /* ray origins and directions, the items in tree order */
  rtcd_uint source_count;
  rtcd_uint first_source_node; /* its source tree's nodes (rtcd_source_node) */
  rtcd_uint source_node_count;
  rtcd_uint first_value; /* its distance bound's grid values */
  float radius;             /* sphere */
  rtcd_vec3 half_extents;   /* box */
} rtcd_device_shape;

/* One pair-direction of a batch on one device, made there from its setup
 * (rtcd_job_setup, rtcd_prepare). Items are the job's possible rays (every
 * source vertex, or every tracked ray), numbered across the batch; rays are
 * the candidates among them, compacted. */
typedef struct {
  rtcd_trace_params params;
  rtcd_uint source;
  rtcd_uint target;
  rtcd_uint first_item;
  rtcd_uint item_count;
  rtcd_uint first_tracked; /* iterative jobs: the job's tracked rays */
  rtcd_uint first_near;    /* full jobs placed on the host: where its near items are (rtcd_near_item) */
} rtcd_device_job;

#ifdef RTCD_HAS_DOUBLE
/* The job a setup makes, with the shapes' traits and the configuration's switches. */
RTCD_INLINE rtcd_device_job rtcd_device_job_of(rtcd_uint config, const rtcd_job_setup* s,
                                               const rtcd_shape_traits* source, const rtcd_shape_traits* target,
                                               const rtcd_box* target_bounds) {
  rtcd_device_job job;
  job.params = rtcd_make_params(config, s, source, target, target_bounds);
  job.source = s->source;
  job.target = s->target;
  job.first_item = s->first_item;
  job.item_count = s->item_count;
  job.first_tracked = s->first_tracked;
  job.first_near = s->first_near;
  return job;
}
#endif

/* A full job's items near its candidate box as bits, one an item of its
 * source (rtcd_near_find on a device; the host's where it places the
 * rays). Words a source of `item_count` items needs: */
RTCD_INLINE rtcd_uint rtcd_near_words(rtcd_uint item_count) { return (item_count + 31) / 32; }

/* Whether a job's near items hold `item`. */
RTCD_INLINE int rtcd_near_item(RTCD_GLOBAL const rtcd_uint* bits, rtcd_uint item) {
  return (int)((bits[item / 32] >> (item % 32)) & 1u);
}

/* A pair of a full batch as the host sends it: its bodies and flags (no
 * RTCD_JOB_ITERATIVE); the device finds its items (rtcd_prepare). */
typedef struct {
  rtcd_uint bodies[2];
  rtcd_uint flags;
} rtcd_full_pair;

RTCD_INLINE rtcd_pair_setup rtcd_setup_of_full(rtcd_full_pair f) {
  rtcd_pair_setup s;
  s.bodies[0] = f.bodies[0];
  s.bodies[1] = f.bodies[1];
  s.flags = f.flags;
  s.moved = 0.0f;
  s.item_count[0] = s.item_count[1] = 0;
  s.first[0] = s.first[1] = 0;
  return s;
}

/* rtcd_pair_setup's words, and where its item counts are among them. */
#define RTCD_PAIR_SETUP_WORDS 8u
#define RTCD_PAIR_COUNTS_WORD 4u

/* A walking pair as a device's batch lists it (rtcd_pair_list): with
 * RTCD_PAIR_RESIDENT among its flags, a pair that walks the rays it kept on
 * this device last step, whole: its setup is row `slot` of last step's pair
 * table, with these flags and this motion. Else its setup is the batch's
 * `slot`th sent after the references. 8 bytes: the slot and the flags
 * share a word (rtcd_pair_ref_of). */
typedef struct {
  rtcd_uint slot_flags;
  float moved;
} rtcd_pair_ref;
#define RTCD_PAIR_REF_WORDS 2u
#define RTCD_PAIR_RESIDENT 16u
#define RTCD_PAIR_FLAG_BITS 5u /* rtcd_pair_setup's flags and RTCD_PAIR_RESIDENT */
#define RTCD_PAIR_MAX_SLOT ((1u << (32u - RTCD_PAIR_FLAG_BITS)) - 1u)
#define RTCD_PAIR_MAX_FLAGS ((1u << RTCD_PAIR_FLAG_BITS) - 1u)

/* The reference to `slot` with `flags` (slot <= RTCD_PAIR_MAX_SLOT). */
RTCD_INLINE rtcd_pair_ref rtcd_pair_ref_of(rtcd_uint slot, rtcd_uint flags, float moved) {
  rtcd_pair_ref r;
  r.slot_flags = slot << RTCD_PAIR_FLAG_BITS | flags;
  r.moved = moved;
  return r;
}
/* A batch whose setups the host made writes no pair table row. */
#define RTCD_NO_SLOT 0xffffffffu

/* A tracked ray on a device: the walk-start fields of the rtcd_outcome that kept it. */
typedef struct {
  rtcd_uint vertex;
  rtcd_int triangle;
  rtcd_int entry;
} rtcd_tracked;

/* A contact or predictive ray, its job (in the batch) and its place among
 * the job's kept rays. */
typedef struct {
  rtcd_outcome outcome;
  rtcd_uint place;
  rtcd_uint job;
} rtcd_report;

/* What the host reads of every job: its kept rays (the vertex rays
 * first); its reports come with their job. */
typedef struct {
  rtcd_uint kept;
  rtcd_uint kept_origins;
} rtcd_job_summary;

#endif
