// The CPU executor shared by the basic and Embree backends: candidate
// selection, the walk and the predictive logic run here through the kernel
// code, parallel over jobs and rays with TBB; a backend supplies only the
// full tracer.
#pragma once

#include <memory>

#include "rtcd/kernel/job.h"
#include "rtcd/kernel/locate.h"
#include "rtcd/kernel/tracer.h"
#include "rtcd/distance_bound.hpp"
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
// testing: those that cannot cross it now are dropped, and of the others
// only those within the watch reach are kept for later walks (kernel/trace.h,
// rtcd_watch_edge), which stop once the pair has moved that far. Negative:
// the job tests no edge.
inline double edge_reach(const rtcd_trace_params& p) { return !p.edges ? -1.0 : p.watch ? double(p.reach) : 0.0; }

// Calls visit_node(n) for each leaf sources.nodes[n] of the source's tree
// whose box, placed in the target's frame as the box around it (in double,
// grown well past rounding), meets the job's overlap box. Its items are a
// superset of the candidates rtcd_place_item takes, found by whole boxes:
// most of a body's items lie far from the overlap and are turned away
// without being placed. A node of edges is turned away too when the
// target's distance bound at its centre, less half its box's diagonal,
// puts every edge in it beyond `reach` (edge_reach) of the surface: one
// lookup instead of a test per edge. Each leaf at most once, in no
// particular order.
template <class VisitNode>
void visit_near_leaves(const RayJob& job, const RaySources& sources, const DistanceBound& target, double reach,
                       const VisitNode& visit_node) {
  if (job.overlap.empty()) return;
  const Eigen::Matrix3d& rotation = job.rotation;
  const Eigen::Matrix3d spread = rotation.cwiseAbs();
  const double scale =
      1.0 + job.translation.norm() + job.overlap.min.cwiseAbs().maxCoeff() + job.overlap.max.cwiseAbs().maxCoeff();
  const Aabb box = job.overlap.grown(1e-9 * scale);
  // Far above the float rounding of the kernel's edge tests.
  const double beyond = reach + 1e-6 * scale;
  auto may_hold = [&](const RaySources::Node& n) {
    const Eigen::Vector3d centre = rotation * (0.5 * (n.lo.cast<double>() + n.hi.cast<double>())) + job.translation;
    const Eigen::Vector3d half = spread * (0.5 * (n.hi.cast<double>() - n.lo.cast<double>()));
    if (!(((centre + half).array() >= box.min.array()).all() && ((centre - half).array() <= box.max.array()).all()))
      return false;
    if (!sources.edges_only(n)) return true;
    return reach >= 0.0 && !(target.lower(centre) > 0.5 * (n.hi - n.lo).cast<double>().norm() + beyond);
  };
  sources.visit_leaves(may_hold, visit_node);
}

// Calls visit(item) for each item of the leaves visit_near_leaves reaches
// (origins and edges): each at most once, in no particular order.
template <class Visit>
void visit_near_items(const RayJob& job, const RaySources& sources, const DistanceBound& target, double reach,
                      const Visit& visit) {
  visit_near_leaves(job, sources, target, reach, [&](uint32_t n) {
    for (uint32_t v : sources.items_of(n)) visit(v);
  });
}

}  // namespace rtcd
