// The thesis' basic traversal: every ray against every triangle, through
// the shared kernel's watertight ray/triangle location. Slow and obvious:
// the reference the other backends are held to.
#include "basic_backend.hpp"

#include "rtcd/kernel/nearest.h"
#include "rtcd/kernel/walk.h"

namespace rtcd {
namespace {

class BasicTracer final : public MeshTracer {
 public:
  explicit BasicTracer(const Mesh& mesh) : mesh_(mesh) {}

  TraceHit first_hit(const rtcd_ray& ray, float t_max) const override {
    TraceHit best;
    best.t = t_max;
    const auto positions = mesh_.positions();
    const auto triangles = mesh_.triangles();
    const auto zero_area = mesh_.zero_area();
    for (size_t i = 0; i < triangles.size(); ++i) {
      if (zero_area[i]) continue;
      const auto& tri = triangles[i];
      const rtcd_location loc = rtcd_locate(&ray, rtcd_v3(positions[tri[0]].x(), positions[tri[0]].y(), positions[tri[0]].z()),
                                            rtcd_v3(positions[tri[1]].x(), positions[tri[1]].y(), positions[tri[1]].z()),
                                            rtcd_v3(positions[tri[2]].x(), positions[tri[2]].y(), positions[tri[2]].z()));
      if (!loc.inside || loc.t_num < 0.0f) continue;
      const float t = loc.t_num / loc.det;
      if (t <= best.t) {
        if (t == best.t && best.triangle >= 0) continue;  // ties: lowest index wins
        best.t = t;
        best.triangle = int32_t(i);
      }
    }
    return best;
  }

  int32_t nearest(const rtcd_vec3& point, float radius) const override {
    const auto positions = mesh_.positions();
    const auto triangles = mesh_.triangles();
    const auto zero_area = mesh_.zero_area();
    auto v = [&](uint32_t i) { return rtcd_v3(positions[i].x(), positions[i].y(), positions[i].z()); };
    int32_t best = -1;
    float best_d2 = radius * radius;
    for (size_t i = 0; i < triangles.size(); ++i) {
      if (zero_area[i]) continue;
      const auto& tri = triangles[i];
      const float d2 = rtcd_point_triangle_distance2(point, v(tri[0]), v(tri[1]), v(tri[2]));
      if (d2 <= best_d2 && (best < 0 || d2 < best_d2)) {
        best_d2 = d2;
        best = int32_t(i);
      }
    }
    return best;
  }

 private:
  const Mesh& mesh_;  // owned by the registered Shape, which outlives the tracer
};

class BasicTracerFactory final : public MeshTracerFactory {
 public:
  std::unique_ptr<MeshTracer> build(const Mesh& mesh) const override { return std::make_unique<BasicTracer>(mesh); }
};

}  // namespace

std::unique_ptr<NarrowPhase> make_basic_narrow_phase(const Config& config) {
  return make_pipeline_narrow_phase("basic", {"cpu (TBB)"}, make_cpu_executor(std::make_unique<BasicTracerFactory>()),
                                    config);
}

}  // namespace rtcd
