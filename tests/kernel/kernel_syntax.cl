/* Compiles the shared kernel headers as OpenCL C 1.2 and calls each entry
 * point, so the C/OpenCL-C subset stays honest. The OpenCL backend's own
 * kernels (backends/opencl/kernels.cl) are compiled by a test of their own. */
#include "rtcd/kernel/bvh.h"
#include "rtcd/kernel/classify.h"
#include "rtcd/kernel/fold.h"
#include "rtcd/kernel/nearest.h"
#include "rtcd/kernel/volumes.h"
#include "rtcd/kernel/walk.h"

/* The smallest tracer trace.h accepts: brute force over one mesh. */
typedef struct {
  __global const rtcd_vec3* positions;
  __global const rtcd_uint* triangles;
  __global const rtcd_int* neighbors;
  __global const rtcd_uchar* zero_area;
  __global const rtcd_fold_face* fold_faces;
  __global const rtcd_uint* ring_first;
  __global const rtcd_int* ring;
} rtcd_tracer;
rtcd_hit rtcd_tracer_first_hit(const rtcd_tracer* t, const rtcd_ray* ray, float t_max) {
  return rtcd_brute_first_hit(ray, t->positions, t->triangles, t->zero_area, 1u, t_max);
}
rtcd_int rtcd_tracer_nearest(const rtcd_tracer* t, rtcd_vec3 point, float radius, float enough) {
  return rtcd_brute_nearest(point, radius, t->positions, t->triangles, t->zero_area, 1u);
}
rtcd_walk_result rtcd_tracer_walk(const rtcd_tracer* t, const rtcd_ray* ray, rtcd_int start, rtcd_uint max_steps) {
  return rtcd_walk(ray, t->positions, t->triangles, t->neighbors, t->zero_area, start, max_steps);
}
int rtcd_tracer_leaves(const rtcd_tracer* t, rtcd_int triangle, rtcd_vec3 direction) {
  return rtcd_dot(direction, t->positions[triangle]) > 0.0f;
}
int rtcd_tracer_fold_free(const rtcd_tracer* t, rtcd_int face, rtcd_vec3 origin, rtcd_vec3 toward, float reach) {
  return rtcd_fold_free(face, origin, toward, reach, t->positions, t->fold_faces, t->ring_first, t->ring);
}
float rtcd_tracer_distance2(const rtcd_tracer* t, rtcd_int triangle, rtcd_vec3 point) {
  return rtcd_point_triangle_distance2(point, t->positions[t->triangles[3 * triangle]],
                                       t->positions[t->triangles[3 * triangle + 1]],
                                       t->positions[t->triangles[3 * triangle + 2]]);
}
#include "rtcd/kernel/trace.h"

__kernel void exercise(__global const rtcd_vec3* positions, __global const rtcd_uint* triangles,
                       __global const rtcd_int* neighbors, __global const rtcd_uchar* zero_area,
                       __global const rtcd_bvh_node* nodes, __global const rtcd_bvh_wide_node* wide,
                       __global const rtcd_bvh_primitive* primitives,
#ifdef RTCD_HAS_DOUBLE
                       __global const rtcd_frame* frames, /* read in place, as the devices read a job's frame */
#endif
                       __global float* out) {
  rtcd_ray ray = rtcd_make_ray(rtcd_v3(0.0f, 0.0f, 0.0f), rtcd_v3(0.0f, 0.0f, 1.0f));
  rtcd_walk_result w = rtcd_walk(&ray, positions, triangles, neighbors, zero_area, 0, 16u);
  rtcd_volume_hit s = rtcd_sphere_line(ray.origin, ray.direction, 1.0f);
  rtcd_volume_hit b = rtcd_box_line(ray.origin, ray.direction, rtcd_v3(1.0f, 1.0f, 1.0f));
  float d2 = rtcd_point_triangle_distance2(ray.origin, positions[0], positions[1], positions[2]);
  int kind = rtcd_classify(w.status, w.t, 1, 0.1f) + rtcd_line_kind(w.status, w.t, 1, 1, 0, 0.1f) +
             rtcd_walked_kind(w.status, w.t, s.status, s.t, 1, 1, 0, 0.1f);
  rtcd_hit h = rtcd_bvh_first_hit(&ray, nodes, 1u, wide, primitives, 1.0f);
  rtcd_int near = rtcd_bvh_nearest(ray.origin, 1.0f, 0.5f, nodes, 1u, wide, primitives);
  rtcd_tracer t;
  rtcd_trace_params p;
  rtcd_candidate c;
  rtcd_outcome o;
  t.positions = positions;
  t.triangles = triangles;
  t.neighbors = neighbors;
  t.zero_area = zero_area;
  t.fold_faces = (__global const rtcd_fold_face*)out;
  t.ring_first = triangles;
  t.ring = neighbors;
  p.watch_lo = p.watch_hi = ray.origin;
  p.extension = p.reach = 0.1f;
  p.max_walk_steps = 8u;
  p.predictive = p.watch = 1;
  p.iterative = 0;
  p.verify = 1;
  p.first_edge = 1u;
  p.edges = 1;
  p.source_radius = 0.0f;
  p.moved = 0.0f;
  c.vertex = 0u;
  c.start = c.entry = 0;
  c.job = 0u;
  c.origin = ray.origin;
  c.direction = ray.direction;
  rtcd_outcome_init(&o, 0u);
  rtcd_full_trace(&t, &p, &c, 1, &o);
  rtcd_walk_trace(&t, &p, &c, &o);
  rtcd_volume_trace(RTCD_TARGET_BOX, 1.0f, ray.origin, &p, &c, &o);
  rtcd_edge_trace(&t, &p, &c, &o);
  rtcd_edge_volume_trace(RTCD_TARGET_SPHERE, 1.0f, ray.origin, &p, &c, &o);
  rtcd_sphere_trace(RTCD_TARGET_BOX, 1.0f, ray.origin, &p, &c, &o);
#ifdef RTCD_HAS_DOUBLE
  kind += rtcd_place_ray(frames, ray.origin, ray.direction, &c.origin, &c.direction);
  kind += rtcd_place_item(frames, &p, 1u, ray.origin, ray.direction, &c.origin, &c.direction);
#endif
  out[get_global_id(0)] = w.t + s.t + b.t + d2 + (float)kind + h.t + (float)near + o.t;
}
