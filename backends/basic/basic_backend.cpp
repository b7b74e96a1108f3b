// The thesis' basic traversal: every ray against every triangle, through
// the shared kernel's watertight ray/triangle location. Slow and obvious:
// the reference the other backends are held to.
#include "basic_backend.hpp"

#include "rtcd/kernel/brute.h"

namespace rtcd {
namespace {

class BasicTracer final : public MeshTracer {
 public:
  explicit BasicTracer(const Mesh& mesh) : mesh_(mesh) {}

  TraceHit first_hit(const rtcd_ray& ray, float t_max) const override {
    const rtcd_hit h = rtcd_brute_first_hit(&ray, positions(), triangles(), mesh_.zero_area().data(),
                                            rtcd_uint(mesh_.triangle_count()), t_max);
    return {h.triangle, h.t};
  }

  int32_t nearest(const rtcd_vec3& point, float radius, float) const override {
    return rtcd_brute_nearest(point, radius, positions(), triangles(), mesh_.zero_area().data(),
                              rtcd_uint(mesh_.triangle_count()));
  }

 private:
  const rtcd_vec3* positions() const { return reinterpret_cast<const rtcd_vec3*>(mesh_.positions().data()); }
  const rtcd_uint* triangles() const { return reinterpret_cast<const rtcd_uint*>(mesh_.triangles().data()); }

  const Mesh& mesh_;  // owned by the registered Shape, which outlives the tracer
};

class BasicTracerFactory final : public MeshTracerFactory {
 public:
  std::unique_ptr<MeshTracer> build(const Mesh& mesh) const override { return std::make_unique<BasicTracer>(mesh); }
};

}  // namespace

std::unique_ptr<NarrowPhase> make_basic_narrow_phase(const BackendOptions& options, const Config& config) {
  return make_pipeline_narrow_phase(options.name(), {"cpu (TBB)"}, make_cpu_executor(make_basic_tracers()), config,
                                    options.threads);
}

std::unique_ptr<MeshTracerFactory> make_basic_tracers() { return std::make_unique<BasicTracerFactory>(); }

}  // namespace rtcd
