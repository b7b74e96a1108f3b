/* Compiles the shared kernel headers as OpenCL C 1.2 and calls each entry
 * point, so the C/OpenCL-C subset stays honest. */
#include "rtcd/kernel/classify.h"
#include "rtcd/kernel/nearest.h"
#include "rtcd/kernel/volumes.h"
#include "rtcd/kernel/walk.h"

__kernel void exercise(__global const rtcd_vec3* positions, __global const rtcd_uint* triangles,
                       __global const rtcd_int* neighbors, __global const rtcd_uchar* zero_area,
                       __global float* out) {
  rtcd_ray ray = rtcd_make_ray(rtcd_v3(0.0f, 0.0f, 0.0f), rtcd_v3(0.0f, 0.0f, 1.0f));
  rtcd_walk_result w = rtcd_walk(&ray, positions, triangles, neighbors, zero_area, 0, 16u);
  rtcd_volume_hit s = rtcd_sphere_line(ray.origin, ray.direction, 1.0f);
  rtcd_volume_hit b = rtcd_box_line(ray.origin, ray.direction, rtcd_v3(1.0f, 1.0f, 1.0f));
  float d2 = rtcd_point_triangle_distance2(ray.origin, positions[0], positions[1], positions[2]);
  int kind = rtcd_classify(w.status, w.t, 1, 0.1f) + rtcd_line_kind(w.status, w.t, 1, 1, 0, 0.1f) +
             rtcd_walked_kind(w.status, w.t, s.status, s.t, 1, 1, 0, 0.1f);
  out[get_global_id(0)] = w.t + s.t + b.t + d2 + (float)kind;
}
