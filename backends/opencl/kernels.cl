/* The OpenCL executor's kernels. The per-ray work is the shared code of
 * core/include/rtcd/kernel (trace.h), run against this file's tracer: the
 * brute-force traversal, or the BVH (four children a node, nearer first) with -DRTCD_BVH. The build
 * inlines every #include (rtcd_embed_kernel), so the binary carries the
 * whole source. */
#include "device_types.h"
#include "rtcd/kernel/bvh.h"
#include "rtcd/kernel/fold.h"
#include "rtcd/kernel/motion.h"
#include "rtcd/kernel/walk.h"

#ifdef RTCD_INJECTED_BUILD_FAILURE
#error "build failure injected for a test (RTCD_OPENCL_FAULT=build)"
#endif

typedef struct {
  __global const rtcd_vec3* positions;
  __global const rtcd_uint* triangles;
  __global const rtcd_int* neighbors;
  __global const rtcd_uchar* zero_area;
  __global const rtcd_vec3* normals;
  __global const rtcd_fold_face* fold_faces;
  __global const rtcd_uint* ring_first;
  __global const rtcd_int* ring;
  __global const rtcd_bvh_node* nodes;
  __global const rtcd_bvh_wide_node* wide;
  __global const rtcd_bvh_primitive* primitives;
  rtcd_uint triangle_count;
  rtcd_uint node_count;
} rtcd_tracer;

RTCD_INLINE rtcd_hit rtcd_tracer_first_hit(const rtcd_tracer* t, const rtcd_ray* ray, float t_max) {
#ifdef RTCD_BVH
  return rtcd_bvh_first_hit(ray, t->nodes, t->node_count, t->wide, t->primitives, t_max);
#else
  return rtcd_brute_first_hit(ray, t->positions, t->triangles, t->zero_area, t->triangle_count, t_max);
#endif
}

/* The brute force always finds the nearest: `enough` only lets a tracer
 * stop sooner. */
RTCD_INLINE rtcd_int rtcd_tracer_nearest(const rtcd_tracer* t, rtcd_vec3 point, float radius, float enough) {
#ifdef RTCD_BVH
  return rtcd_bvh_nearest(point, radius, enough, t->nodes, t->node_count, t->wide, t->primitives);
#else
  return rtcd_brute_nearest(point, radius, t->positions, t->triangles, t->zero_area, t->triangle_count);
#endif
}

RTCD_INLINE rtcd_walk_result rtcd_tracer_walk(const rtcd_tracer* t, const rtcd_ray* ray, rtcd_int start,
                                              rtcd_uint max_steps) {
  return rtcd_walk(ray, t->positions, t->triangles, t->neighbors, t->zero_area, start, max_steps);
}

RTCD_INLINE int rtcd_tracer_leaves(const rtcd_tracer* t, rtcd_int triangle, rtcd_vec3 direction) {
  return rtcd_dot(direction, t->normals[triangle]) > 0.0f;
}

RTCD_INLINE int rtcd_tracer_fold_free(const rtcd_tracer* t, rtcd_int face, rtcd_vec3 origin, rtcd_vec3 toward,
                                      float reach) {
  return rtcd_fold_free(face, origin, toward, reach, t->normals, t->fold_faces, t->ring_first, t->ring);
}

RTCD_INLINE float rtcd_tracer_distance2(const rtcd_tracer* t, rtcd_int triangle, rtcd_vec3 point) {
  return rtcd_point_triangle_distance2(point, t->positions[t->triangles[3 * triangle]],
                                       t->positions[t->triangles[3 * triangle + 1]],
                                       t->positions[t->triangles[3 * triangle + 2]]);
}

#include "rtcd/kernel/trace.h"

/* The batch's items the device counted (`items`, rtcd_prepare), up to the
 * room the host made. Within the room, a job that did not fit leaves items
 * of no job (RTCD_NO_JOB). The kernels over items or rays take them in
 * strides of the launch (RTCD_FOR_EACH), whose size the host guesses. */
#define RTCD_NO_JOB 0xffffffffu
RTCD_INLINE rtcd_uint rtcd_items_in(__global const rtcd_uint* items, rtcd_uint room) { return min(*items, room); }
#define RTCD_FOR_EACH(i, n) for (i = get_global_id(0); i < (n); i += get_global_size(0))

#ifdef RTCD_HAS_DOUBLE
/* What a device reads to find a full job's items: the shapes' source
 * trees (rtcd_source_node, by first_source_node) and the items in tree
 * order (RaySources::order, by first_source), the distance bounds (by
 * shape) and their grids' values (by first_value). */
typedef struct {
  __global const rtcd_device_shape* shapes;
  __global const rtcd_source_node* nodes;
  __global const rtcd_uint* order;
  __global const rtcd_distance_grid* grids;
  __global const float* values;
} rtcd_near_data;

/* A full job's near leaves are merged this many at most (rtcd_near_list);
 * past it their items are written as bits. */
#define RTCD_NEAR_MERGE 8u

/* A full job's near leaves (kernel/near.h's search of its source tree, as
 * the CPU executors run it): those near its candidate box, in `list`, or,
 * past RTCD_NEAR_MERGE, their items as bits at `bits`, one an item of the
 * source (rtcd_near_words of them). Returns how many items they hold;
 * *listed is how many leaves were found, up to RTCD_NEAR_MERGE + 1. */
RTCD_INLINE rtcd_uint rtcd_near_find(const rtcd_near_data* data, const rtcd_device_job* job,
                                     const rtcd_shape_traits* source_traits, const rtcd_frame* frame,
                                     rtcd_uint* list, rtcd_uint* listed, __global rtcd_uint* bits) {
  const rtcd_device_shape shape = data->shapes[job->source];
  const rtcd_distance_grid grid = data->grids[job->target];
  __global const float* values = data->values + data->shapes[job->target].first_value;
  rtcd_uint leaf, count = 0, k, r;
  rtcd_source_tree tree;
  rtcd_near_search search;
  tree.nodes = data->nodes + shape.first_source_node;
  tree.order = data->order + shape.first_source;
  tree.node_count = shape.source_node_count;
  tree.first_edge = source_traits->first_edge;
  tree.sphere = source_traits->sphere_radius > 0.0f;
  rtcd_near_begin(&search, frame, rtcd_edge_reach(&job->params), &tree);
  *listed = 0;
  while ((leaf = rtcd_near_next(&search, &tree, &grid, values)) != RTCD_NO_LEAF) {
    count += tree.nodes[leaf].end - tree.nodes[leaf].begin;
    if (*listed < RTCD_NEAR_MERGE) {
      list[(*listed)++] = leaf;
      continue;
    }
    if (*listed == RTCD_NEAR_MERGE) { /* the list is full: bits from here on */
      for (k = 0; k < rtcd_near_words(shape.source_count); ++k) bits[k] = 0;
      for (r = 0; r < RTCD_NEAR_MERGE; ++r)
        for (k = tree.nodes[list[r]].begin; k < tree.nodes[list[r]].end; ++k)
          bits[tree.order[k] / 32] |= 1u << (tree.order[k] % 32);
      ++*listed;
    }
    for (k = tree.nodes[leaf].begin; k < tree.nodes[leaf].end; ++k)
      bits[tree.order[k] / 32] |= 1u << (tree.order[k] % 32);
  }
  return count;
}

/* The items rtcd_near_find found, in item order, at `out`: a merge of its
 * leaves' items (each leaf's in order, `items` the source's, sorted a
 * leaf), the least head next; or the bits set, word by word. */
RTCD_INLINE void rtcd_near_list(const rtcd_near_data* data, rtcd_uint source, const rtcd_uint* list,
                                rtcd_uint listed, __global const rtcd_uint* items, __global const rtcd_uint* bits,
                                __global rtcd_uint* out) {
  const rtcd_device_shape shape = data->shapes[source];
  __global const rtcd_source_node* nodes = data->nodes + shape.first_source_node;
  rtcd_uint at[RTCD_NEAR_MERGE], end[RTCD_NEAR_MERGE], head[RTCD_NEAR_MERGE];
  rtcd_uint runs = 0, r, n = 0, w;
  items += shape.first_source;
  if (listed > RTCD_NEAR_MERGE) {
    for (w = 0; w < rtcd_near_words(shape.source_count); ++w) {
      rtcd_uint word = bits[w];
      while (word != 0) {
        const rtcd_uint lowest = word & (~word + 1u);
        out[n++] = 32 * w + 31 - clz(lowest);
        word ^= lowest;
      }
    }
    return;
  }
  for (r = 0; r < listed; ++r) {
    at[runs] = nodes[list[r]].begin;
    end[runs] = nodes[list[r]].end;
    if (at[runs] == end[runs]) continue;
    head[runs] = items[at[runs]];
    ++runs;
  }
  while (runs > 0) {
    rtcd_uint least = 0;
    for (r = 1; r < runs; ++r) least = head[r] < head[least] ? r : least;
    out[n++] = head[least];
    if (++at[least] < end[least]) {
      head[least] = items[at[least]];
    } else { /* the last run takes its place */
      --runs;
      at[least] = at[runs];
      end[least] = end[runs];
      head[least] = head[runs];
    }
  }
}

/* One job, before its items, made from its pair's setup (job j is
 * direction j % 2 of pair j / 2) as the host makes it: its limits from the
 * pair's motion (from its bodies' poses of the last step, `before`, to
 * this step's: rtcd_pair_motion), the configuration's limit settings and
 * its bodies' shapes' scales (rtcd_derive_limits), its parameters
 * (rtcd_make_params) and its frame from its bodies' poses
 * (rtcd_relative_frame). A walking job's items are its tracked rays, from
 * its first item (rtcd_pair_list); a full job finds its own
 * (rtcd_near_find; bits at `near`, near_stride words a job) and takes
 * room for them in the batch's item list from `items` on (an atomic count,
 * so jobs lie in any order, each its items in order), while they fit in
 * `room`; past it the count still grows, and the host runs the batch again
 * with room for it. Each item's job goes to `item_jobs`. */
__kernel void rtcd_prepare(__global const rtcd_pair_setup* setups, rtcd_uint job_count, rtcd_uint config,
                           double displacement_threshold, double distance_extension, rtcd_uint max_walk_steps,
                           rtcd_uint limits_set, __global const rtcd_device_shape* shapes,
                           __global const rtcd_shape_traits* traits, __global const rtcd_box* bounds,
                           __global const rtcd_shape_scale* scales, __global const rtcd_source_node* source_nodes,
                           __global const rtcd_uint* source_order, __global const rtcd_uint* leaf_items,
                           __global const rtcd_distance_grid* grids,
                           __global const float* grid_values, __global rtcd_uint* near, rtcd_uint near_stride,
                           __global const rtcd_pose* poses, __global const rtcd_pose* before,
                           __global const rtcd_uint* body_shapes, __global rtcd_device_job* jobs,
                           __global const rtcd_uint* first_items, __global rtcd_frame* frames,
                           volatile __global rtcd_uint* items, rtcd_uint room, __global rtcd_uint* vertices,
                           __global rtcd_uint* item_jobs) {
  rtcd_uint j = get_global_id(0);
  rtcd_uint k, shape_0, shape_1;
  double motion = 0.0;
  rtcd_pair_setup pair;
  rtcd_limit_settings settings;
  rtcd_shape_scale scale_0, scale_1;
  rtcd_job_setup s;
  rtcd_device_job job;
  rtcd_shape_traits source_traits, target_traits;
  rtcd_pose source, target;
  rtcd_box source_bounds, target_bounds;
  rtcd_frame frame;
  rtcd_near_data data;
  rtcd_uint list[RTCD_NEAR_MERGE], listed;
  if (j >= job_count) return;
  pair = setups[j / 2];
  settings.displacement_threshold = displacement_threshold;
  settings.distance_extension = distance_extension;
  settings.max_walk_steps = max_walk_steps;
  settings.set = limits_set;
  shape_0 = body_shapes[pair.bodies[0]];
  shape_1 = body_shapes[pair.bodies[1]];
  scale_0 = scales[shape_0];
  scale_1 = scales[shape_1];
  if (pair.flags & RTCD_PAIR_MOTION)
    motion = rtcd_bodies_motion(pair.bodies[0], pair.bodies[1], before, poses, scale_0.radius, scale_1.radius);
  s = rtcd_direction_setup(&pair, j % 2, (pair.flags & RTCD_JOB_ITERATIVE) ? first_items[j - j % 2] : 0u, motion,
                           config, &settings, shape_0, shape_1, &scale_0, &scale_1);
  source_traits = traits[s.source];
  target_traits = traits[s.target];
  source_bounds = bounds[s.source];
  target_bounds = bounds[s.target];
  job = rtcd_device_job_of(config, &s, &source_traits, &target_traits, &target_bounds);
  source = poses[s.source_body];
  target = poses[s.target_body];
  rtcd_relative_frame(&source, &target, &source_bounds, &target_bounds, s.extension, &frame);
  frames[j] = frame;
  if (!job.params.iterative) {
    data.shapes = shapes;
    data.nodes = source_nodes;
    data.order = source_order;
    data.grids = grids;
    data.values = grid_values;
    near += (size_t)j * near_stride;
    job.item_count = rtcd_near_find(&data, &job, &source_traits, &frame, list, &listed, near);
    job.first_item = job.item_count > 0 ? atomic_add(items, job.item_count) : 0u;
    if (job.item_count > room || job.first_item > room - job.item_count) { /* past the room: the host runs it again */
      for (k = job.first_item; k < room; ++k) item_jobs[k] = RTCD_NO_JOB; /* items no job holds */
      job.item_count = 0;
      job.first_item = 0;
    } else if (job.item_count > 0) {
      rtcd_near_list(&data, job.source, list, listed, leaf_items, near, vertices + job.first_item);
    }
  }
  jobs[j] = job;
  for (k = 0; k < job.item_count; ++k) item_jobs[job.first_item + k] = j;
}

/* Item i: the possible ray placed in the target's frame (rtcd_place_ray, in
 * double) as candidate c; 1 when it is a candidate. */
RTCD_INLINE int rtcd_select_item(rtcd_uint i, __global const rtcd_device_job* jobs,
                                 __global const rtcd_uint* item_jobs, __global const rtcd_frame* frames,
                                 __global const rtcd_device_shape* shapes, __global const rtcd_vec3* origins,
                                 __global const rtcd_vec3* directions, __global const rtcd_uint* vertices,
                                 __global const rtcd_tracked* tracked, rtcd_candidate* c) {
  rtcd_uint j = item_jobs[i];
  rtcd_device_job job = jobs[j];
  rtcd_uint s;
  c->job = j;
  if (job.params.iterative) {
    rtcd_tracked r = tracked[job.first_tracked + (i - job.first_item)];
    c->vertex = r.vertex;
    c->start = r.triangle;
    c->entry = r.entry;
  } else {
    c->vertex = vertices[i];
    c->start = -1;
    c->entry = -1;
  }
  s = shapes[job.source].first_source + c->vertex;
  c->origin = rtcd_v3(0.0f, 0.0f, 0.0f);
  c->direction = c->origin;
  return rtcd_place_item(frames + j, &job.params, c->vertex, origins[s], directions[s], &c->origin, &c->direction);
}

/* Compacted layout, each item: placed and flagged, for rtcd_count and
 * rtcd_scatter. */
__kernel void rtcd_select(__global const rtcd_device_job* jobs, __global const rtcd_uint* item_jobs,
                          __global const rtcd_frame* frames, __global const rtcd_uint* items, rtcd_uint room,
                          __global const rtcd_device_shape* shapes, __global const rtcd_vec3* origins,
                          __global const rtcd_vec3* directions, __global const rtcd_uint* vertices,
                          __global const rtcd_tracked* tracked, __global rtcd_uchar* flags,
                          __global rtcd_candidate* staging) {
  const rtcd_uint n = rtcd_items_in(items, room);
  rtcd_uint i;
  rtcd_candidate c;
  RTCD_FOR_EACH(i, n) {
    if (item_jobs[i] == RTCD_NO_JOB) {
      flags[i] = 0;
      continue;
    }
    flags[i] = (rtcd_uchar)rtcd_select_item(i, jobs, item_jobs, frames, shapes, origins, directions, vertices,
                                            tracked, &c);
    staging[i] = c;
  }
}
#endif

/* One job: its candidates' places in its compacted list (a prefix sum over
 * its items' flags, in item order, so rays keep the CPU's order). */
__kernel void rtcd_count(__global const rtcd_device_job* jobs, rtcd_uint job_count, __global const rtcd_uchar* flags,
                         __global rtcd_uint* slots, __global rtcd_uint* counts) {
  rtcd_uint j = get_global_id(0);
  rtcd_uint n = 0, k;
  rtcd_device_job job;
  if (j >= job_count) return;
  job = jobs[j];
  for (k = 0; k < job.item_count; ++k) {
    slots[job.first_item + k] = n;
    n += flags[job.first_item + k];
  }
  counts[j] = n;
}

/* The job scans (rtcd_offsets, rtcd_total) run as one work-group of up to
 * this many work-items (the host's kGroupSize): each takes a share of the
 * jobs in order, the shares' sums are scanned in local memory, and each
 * work-item writes its share's prefixes, so no single work-item reads every
 * job (a batch holds thousands). Integer sums: any split gives the same. */
#define RTCD_SCAN_WIDTH 64

/* Work-item `lid` of `width`: its share [*begin, *end) of n jobs. */
RTCD_INLINE void rtcd_scan_share(rtcd_uint n, rtcd_uint lid, rtcd_uint width, rtcd_uint* begin, rtcd_uint* end) {
  rtcd_uint chunk = (n + width - 1) / width;
  *begin = min(n, lid * chunk);
  *end = min(n, *begin + chunk);
}

/* The shares' sums in place of their exclusive prefixes; returns the total. */
RTCD_INLINE rtcd_uint rtcd_scan_shares(__local rtcd_uint* partial, rtcd_uint width) {
  rtcd_uint k, sum = 0;
  for (k = 0; k < width; ++k) {
    rtcd_uint c = partial[k];
    partial[k] = sum;
    sum += c;
  }
  return sum;
}

/* Job j's count among `counts`: pairs of words (job 2p's, then 2p + 1's)
 * `pair_stride` words apart from `first_word` on. */
RTCD_INLINE rtcd_uint rtcd_job_count(__global const rtcd_uint* counts, rtcd_uint first_word, rtcd_uint pair_stride,
                                     rtcd_uint j) {
  return counts[first_word + j / 2 * pair_stride + j % 2];
}

/* Each job's first (an exclusive prefix sum of the jobs' counts) and,
 * after the last job, the total, by the work-group's first RTCD_SCAN_WIDTH
 * work-items (`partial` their local sums). */
RTCD_INLINE void rtcd_scan_counts(__global const rtcd_uint* counts, rtcd_uint job_count, __global rtcd_uint* firsts,
                                  rtcd_uint first_word, rtcd_uint pair_stride, __local rtcd_uint* partial) {
  const rtcd_uint lid = get_local_id(0), width = min((rtcd_uint)get_local_size(0), (rtcd_uint)RTCD_SCAN_WIDTH);
  rtcd_uint j, begin = 0, end = 0, n = 0;
  if (lid < width) {
    rtcd_scan_share(job_count, lid, width, &begin, &end);
    for (j = begin; j < end; ++j) n += rtcd_job_count(counts, first_word, pair_stride, j);
    partial[lid] = n;
  }
  barrier(CLK_LOCAL_MEM_FENCE);
  if (lid == 0) firsts[job_count] = rtcd_scan_shares(partial, width);
  barrier(CLK_LOCAL_MEM_FENCE);
  if (lid >= width) return;
  n = partial[lid];
  for (j = begin; j < end; ++j) {
    firsts[j] = n;
    n += rtcd_job_count(counts, first_word, pair_stride, j);
  }
}

/* The batch's ray list from rtcd_count's counts (first_word 0, stride 2),
 * which bounds rtcd_trace, so no count goes through the host. One
 * work-group. */
__kernel void rtcd_offsets(__global const rtcd_uint* counts, rtcd_uint job_count, __global rtcd_uint* firsts) {
  __local rtcd_uint partial[RTCD_SCAN_WIDTH];
  rtcd_scan_counts(counts, job_count, firsts, 0u, 2u, partial);
}

/* The batch's pairs' setups (rtcd_prepare reads them) from what the host
 * sent, `list`: for a full batch (ref_count 0) a rtcd_full_pair a pair,
 * whose items the device finds (rtcd_prepare counts them into `items`,
 * 0 from here); for a walking batch (ref_count pairs), a reference a pair
 * and the setups the references without RTCD_PAIR_RESIDENT name, a
 * resident pair's setup its row of the last step's pair table (`before`:
 * its bodies and its kept rays, which it walks whole) with the reference's
 * flags and motion, and then the batch's item list from the setups' item
 * counts, as rtcd_offsets, its length in `items`. One work-group. */
__kernel void rtcd_pair_list(__global const rtcd_uint* list, rtcd_uint job_count, rtcd_uint ref_count,
                             __global const rtcd_pair_setup* before, __global rtcd_pair_setup* setups,
                             __global rtcd_uint* first_items, __global rtcd_uint* items) {
  __local rtcd_uint partial[RTCD_SCAN_WIDTH];
  __global const rtcd_full_pair* full = (__global const rtcd_full_pair*)list;
  __global const rtcd_pair_ref* refs = (__global const rtcd_pair_ref*)list;
  __global const rtcd_pair_setup* sent = (__global const rtcd_pair_setup*)(list + ref_count * RTCD_PAIR_REF_WORDS);
  rtcd_uint p;
  for (p = get_local_id(0); p < job_count / 2; p += get_local_size(0)) {
    rtcd_pair_setup s;
    if (ref_count == 0) {
      s = rtcd_setup_of_full(full[p]);
    } else {
      const rtcd_pair_ref r = refs[p];
      const rtcd_uint slot = r.slot_flags >> RTCD_PAIR_FLAG_BITS, flags = r.slot_flags & RTCD_PAIR_MAX_FLAGS;
      if (flags & RTCD_PAIR_RESIDENT) {
        s = before[slot];
        s.flags = flags & ~RTCD_PAIR_RESIDENT;
        s.moved = r.moved;
      } else {
        s = sent[slot];
      }
    }
    setups[p] = s;
  }
  barrier(CLK_GLOBAL_MEM_FENCE); /* a full batch's counts are 0: its first items too */
  rtcd_scan_counts((__global const rtcd_uint*)setups, job_count, first_items,
                   RTCD_PAIR_COUNTS_WORD, RTCD_PAIR_SETUP_WORDS, partial);
  if (get_local_id(0) == 0) *items = first_items[job_count];
}

/* Each item: a candidate moves to its place in the batch's ray list. */
__kernel void rtcd_scatter(__global const rtcd_uint* item_jobs, __global const rtcd_uint* first_rays,
                           __global const rtcd_uint* items, rtcd_uint room, __global const rtcd_uchar* flags,
                           __global const rtcd_uint* slots, __global const rtcd_candidate* staging,
                           __global rtcd_candidate* rays) {
  const rtcd_uint n = rtcd_items_in(items, room);
  rtcd_uint i;
  RTCD_FOR_EACH(i, n) {
    if (flags[i]) rays[first_rays[item_jobs[i]] + slots[i]] = staging[i];
  }
}

/* One candidate ray: its full trace, or its walks (trace.h). */
RTCD_INLINE rtcd_outcome rtcd_trace_candidate(const rtcd_candidate* c, __global const rtcd_device_job* jobs,
                                              __global const rtcd_device_shape* shapes,
                                              __global const rtcd_vec3* positions, __global const rtcd_uint* triangles,
                                              __global const rtcd_int* neighbors, __global const rtcd_uchar* zero_area,
                                              __global const rtcd_vec3* normals,
                                              __global const rtcd_fold_face* fold_faces,
                                              __global const rtcd_uint* ring_first, __global const rtcd_int* ring,
                                              __global const rtcd_bvh_node* nodes,
                                              __global const rtcd_bvh_wide_node* wide,
                                              __global const rtcd_bvh_primitive* primitives) {
  rtcd_trace_params p = jobs[c->job].params;
  rtcd_device_shape shape = shapes[jobs[c->job].target];
  int item = rtcd_item_kind(shape.kind, &p, c->vertex);
  rtcd_outcome o;
  rtcd_outcome_init(&o, c->vertex);
  if (shape.kind == RTCD_TARGET_MESH) {
    rtcd_tracer t;
    t.positions = positions + shape.first_vertex;
    t.triangles = triangles + 3 * shape.first_triangle;
    t.neighbors = neighbors + 3 * shape.first_triangle;
    t.zero_area = zero_area + shape.first_triangle;
    t.normals = normals + shape.first_triangle;
    t.fold_faces = fold_faces + shape.first_triangle;
    t.ring_first = ring_first + shape.first_triangle;
    t.ring = ring;
    t.nodes = nodes + shape.first_node;
    t.wide = wide + shape.first_wide;
    t.primitives = primitives + shape.first_primitive;
    t.triangle_count = shape.triangle_count;
    t.node_count = shape.node_count;
    if (item != RTCD_ITEM_ORIGIN) rtcd_edge_trace(&t, &p, c, &o);
    else if (p.iterative) rtcd_walk_trace(&t, &p, c, &o);
    else rtcd_full_trace(&t, &p, c, 0, &o);
  } else if (item == RTCD_ITEM_SPHERE) {
    rtcd_sphere_trace(shape.kind, shape.radius, shape.half_extents, &p, c, &o);
  } else if (item == RTCD_ITEM_EDGE) {
    rtcd_edge_volume_trace(shape.kind, shape.radius, shape.half_extents, &p, c, &o);
  } else {
    rtcd_volume_trace(shape.kind, shape.radius, shape.half_extents, &p, c, &o);
  }
  return o;
}

/* Compacted layout: each candidate ray of the batch's list, whose length
 * (first_rays[job_count]) the device counted, traced. */
__kernel void rtcd_trace(__global const rtcd_device_job* jobs, __global const rtcd_device_shape* shapes,
                         __global const rtcd_vec3* positions, __global const rtcd_uint* triangles,
                         __global const rtcd_int* neighbors, __global const rtcd_uchar* zero_area,
                         __global const rtcd_vec3* normals, __global const rtcd_fold_face* fold_faces,
                         __global const rtcd_uint* ring_first, __global const rtcd_int* ring,
                         __global const rtcd_bvh_node* nodes, __global const rtcd_bvh_wide_node* wide,
                         __global const rtcd_bvh_primitive* primitives, __global const rtcd_candidate* rays,
                         __global const rtcd_uint* first_rays, rtcd_uint job_count,
                         __global rtcd_outcome* outcomes) {
  const rtcd_uint n = first_rays[job_count];
  rtcd_uint i;
  RTCD_FOR_EACH(i, n) {
    const rtcd_candidate c = rays[i];
    outcomes[i] = rtcd_trace_candidate(&c, jobs, shapes, positions, triangles, neighbors, zero_area, normals,
                                       fold_faces, ring_first, ring, nodes, wide, primitives);
  }
}

#ifdef RTCD_HAS_DOUBLE
/* Grid layout (Figure 2.6): each item, a candidate or not, placed and
 * traced in place; the host keeps the flagged ones. */
__kernel void rtcd_trace_items(__global const rtcd_device_job* jobs, __global const rtcd_device_shape* shapes,
                               __global const rtcd_vec3* positions, __global const rtcd_uint* triangles,
                               __global const rtcd_int* neighbors, __global const rtcd_uchar* zero_area,
                               __global const rtcd_vec3* normals, __global const rtcd_fold_face* fold_faces,
                               __global const rtcd_uint* ring_first, __global const rtcd_int* ring,
                               __global const rtcd_bvh_node* nodes, __global const rtcd_bvh_wide_node* wide,
                               __global const rtcd_bvh_primitive* primitives,
                               __global const rtcd_uint* item_jobs, __global const rtcd_frame* frames,
                               __global const rtcd_uint* items, rtcd_uint room, __global const rtcd_vec3* origins,
                               __global const rtcd_vec3* directions, __global const rtcd_uint* vertices,
                               __global const rtcd_tracked* tracked, __global rtcd_uchar* flags,
                               __global rtcd_outcome* outcomes) {
  const rtcd_uint n = rtcd_items_in(items, room);
  rtcd_uint i;
  RTCD_FOR_EACH(i, n) {
    rtcd_candidate c;
    const int flag = item_jobs[i] != RTCD_NO_JOB &&
                     rtcd_select_item(i, jobs, item_jobs, frames, shapes, origins, directions, vertices, tracked, &c);
    flags[i] = (rtcd_uchar)flag;
    if (flag)
      outcomes[i] = rtcd_trace_candidate(&c, jobs, shapes, positions, triangles, neighbors, zero_area, normals,
                                         fold_faces, ring_first, ring, nodes, wide, primitives);
  }
}
#endif

/* A job's rays, in order: its flagged items (grid layout) or its compacted
 * rays (`firsts` and `counts` by job). The first, and one past the last. */
#define RTCD_JOB_RAYS(j, grid, firsts, counts)      \
  first = (grid) ? jobs[j].first_item : firsts[j]; \
  end = first + ((grid) ? jobs[j].item_count : counts[j])

/* One job's outcomes counted (kernel/tally.h) for rtcd_total. */
__kernel void rtcd_tallies(__global const rtcd_device_job* jobs, rtcd_uint job_count, rtcd_uint grid,
                           __global const rtcd_uint* firsts, __global const rtcd_uint* counts,
                           __global const rtcd_uchar* flags, __global const rtcd_outcome* outcomes,
                           __global rtcd_tally* tallies) {
  rtcd_uint j = get_global_id(0);
  rtcd_uint first, end, k;
  int iterative;
  rtcd_tally t;
  if (j >= job_count) return;
  RTCD_JOB_RAYS(j, grid, firsts, counts);
  iterative = jobs[j].params.iterative;
  rtcd_tally_clear(&t);
  for (k = first; k < end; ++k) {
    rtcd_outcome o;
    if (grid && !flags[k]) continue;
    o = outcomes[k];
    rtcd_tally_count(&t, &o, iterative);
  }
  tallies[j] = t;
}

/* Each job's first kept ray and first report (the kept rays and the
 * contacts and predictive rays laid out one job after another), what the
 * host reads of it, and the batch's counters summed. One work-group, as
 * rtcd_offsets; `firsts` holds the kept rays' prefixes, then the reports'. */
__kernel void rtcd_total(__global const rtcd_tally* tallies, rtcd_uint job_count, __global rtcd_uint* firsts,
                         __global rtcd_job_summary* summaries, __global rtcd_tally* total) {
  __local rtcd_uint kept[RTCD_SCAN_WIDTH], reported[RTCD_SCAN_WIDTH];
  __local rtcd_tally sums[RTCD_SCAN_WIDTH];
  const rtcd_uint lid = get_local_id(0), width = min((rtcd_uint)get_local_size(0), (rtcd_uint)RTCD_SCAN_WIDTH);
  __global rtcd_uint* first_kept = firsts;
  __global rtcd_uint* first_reports = firsts + job_count + 1;
  rtcd_uint j, k, begin = 0, end = 0, n = 0, r = 0;
  if (lid < width) {
    rtcd_tally sum;
    rtcd_tally_clear(&sum);
    rtcd_scan_share(job_count, lid, width, &begin, &end);
    for (j = begin; j < end; ++j) {
      rtcd_tally t = tallies[j];
      rtcd_job_summary s;
      s.kept = (rtcd_uint)t.kept;
      s.kept_origins = (rtcd_uint)t.kept_origins;
      summaries[j] = s;
      n += s.kept;
      r += (rtcd_uint)(t.contacts + t.predictive);
      rtcd_tally_add(&sum, &t);
    }
    kept[lid] = n;
    reported[lid] = r;
    sums[lid] = sum;
  }
  barrier(CLK_LOCAL_MEM_FENCE);
  if (lid == 0) {
    rtcd_tally all;
    rtcd_tally_clear(&all);
    for (k = 0; k < width; ++k) {
      rtcd_tally t = sums[k];
      rtcd_tally_add(&all, &t);
    }
    *total = all;
    first_kept[job_count] = rtcd_scan_shares(kept, width);
    first_reports[job_count] = rtcd_scan_shares(reported, width);
  }
  barrier(CLK_LOCAL_MEM_FENCE);
  if (lid >= width) return;
  n = kept[lid];
  r = reported[lid];
  for (j = begin; j < end; ++j) {
    first_kept[j] = n;
    first_reports[j] = r;
    n += (rtcd_uint)tallies[j].kept;
    r += (rtcd_uint)(tallies[j].contacts + tallies[j].predictive);
  }
}

/* One job's outcomes laid out: the rays it goes on tracking (every outcome
 * but the dropped ones, in order) from kept_base + its first kept ray on,
 * where the next step's walks read them, so they stay on the device; and
 * those that report (contacts and predictive rays), in order, each with
 * its job and its place among the job's kept rays, so the host reads these
 * whole and the kept rays only for recovery. Where the device made the
 * setups, its pair's row of the step's pair table (from slot_base on): the
 * bodies, and the direction's kept rays, first and count, for next step's
 * walks (rtcd_pair_list). */
__kernel void rtcd_lay_out(__global const rtcd_device_job* jobs, rtcd_uint job_count, rtcd_uint grid,
                           __global const rtcd_uint* firsts, __global const rtcd_uint* counts,
                           __global const rtcd_uchar* flags, __global const rtcd_outcome* outcomes,
                           __global const rtcd_uint* laid_out, rtcd_uint kept_base, __global rtcd_tracked* kept,
                           __global rtcd_report* reports, __global const rtcd_pair_setup* setups,
                           rtcd_uint slot_base, __global rtcd_pair_setup* table) {
  rtcd_uint j = get_global_id(0);
  rtcd_uint first, end, k, place = 0;
  __global rtcd_tracked* keep;
  __global rtcd_report* report;
  if (j >= job_count) return;
  RTCD_JOB_RAYS(j, grid, firsts, counts);
  if (slot_base != RTCD_NO_SLOT) {
    __global rtcd_pair_setup* row = table + slot_base + j / 2;
    if (j % 2 == 0) {
      row->bodies[0] = setups[j / 2].bodies[0];
      row->bodies[1] = setups[j / 2].bodies[1];
      row->flags = 0;
      row->moved = 0.0f;
    }
    row->item_count[j % 2] = laid_out[j + 1] - laid_out[j];
    row->first[j % 2] = kept_base + laid_out[j];
  }
  keep = kept + kept_base + laid_out[j];
  report = reports + laid_out[job_count + 1 + j];
  for (k = first; k < end; ++k) {
    rtcd_outcome o;
    if (grid && !flags[k]) continue;
    o = outcomes[k];
    if (o.kind == RTCD_RAY_DROPPED) continue;
    keep->vertex = o.vertex;
    keep->triangle = o.triangle;
    keep->entry = o.entry;
    ++keep;
    if (o.kind == RTCD_RAY_PENETRATING || o.kind == RTCD_RAY_PREDICTIVE) {
      report->outcome = o;
      report->place = place;
      report->job = j;
      ++report;
    }
    ++place;
  }
}
