// The CPU executor shared by the basic and Embree backends: candidate
// selection, the walk and the predictive logic run here through the kernel
// code, parallel over jobs and rays with TBB; a backend supplies only the
// full tracer.
#pragma once

#include <memory>

#include "rtcd/kernel/job.h"
#include "rtcd/kernel/locate.h"
#include "rtcd/kernel/tracer.h"
#include "rtcd/near_search.hpp"
#include "rtcd/step_pipeline.hpp"

namespace rtcd {

// First hit of a ray with one mesh, in the mesh's local frame.
struct TraceHit {
  int32_t triangle = -1;  // -1: nothing within range
  float t = 0.0f;
};

// A full tracer built once for one mesh shape.
class MeshTracer {
 public:
  virtual ~MeshTracer() = default;
  // Nearest triangle met by origin + t * direction with 0 <= t <= t_max,
  // from either side; zero-area triangles are never hit.
  virtual TraceHit first_hit(const rtcd_ray& ray, float t_max) const = 0;
  // A triangle nearest to `point` within `radius` (ties: the lowest id, the
  // rule of kernel/tracer.h), or -1; zero-area triangles are never
  // returned. A tracer may return instead any triangle within `enough`
  // (0: never), the first it meets.
  virtual int32_t nearest(const rtcd_vec3& point, float radius, float enough) const = 0;
};

class MeshTracerFactory {
 public:
  virtual ~MeshTracerFactory() = default;
  virtual std::unique_ptr<MeshTracer> build(const Mesh& mesh) const = 0;
};

std::unique_ptr<RayExecutor> make_cpu_executor(std::unique_ptr<MeshTracerFactory> tracers);

// What every executor derives from a job the same way, for the per-ray code
// of kernel/trace.h: the per-ray parameters (rtcd_make_params, from the
// job's setup, the shapes' traits and the configuration's switches, which a
// device is sent instead), the transform and candidate box for rtcd_place_ray.
rtcd_trace_params make_trace_params(const RayJob& job, const Shape& source, const Shape& target, const Config& config);
rtcd_frame make_frame(const RayJob& job);
rtcd_job_setup job_setup(const RayJob& job, const Config& config);  // its items' fields left 0
rtcd_shape_traits shape_traits(const Shape& shape);
rtcd_uint config_flags(const Config& config);

// How far from the target's surface a full job's edges are still worth
// testing (rtcd_edge_reach).
inline double edge_reach(const rtcd_trace_params& p) { return rtcd_edge_reach(&p); }

}  // namespace rtcd
