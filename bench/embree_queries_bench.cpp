// Embree's ways of tracing the same rays, to choose the full tracer's:
// one ray at a time (rtcIntersect1, what the Embree backend does), packets
// of 8 (rtcIntersect8) and streams (rtcIntersect1M, coherent or not). The
// rays are a full step's of the resting pair in narrow_phase_bench.cpp:
// each body's vertices near the other's box, inward rays to any distance
// and outward (predictive) rays to the distance extension, in the target's
// frame. The `differing hits` counter gives the rays whose hit (triangle
// or distance) differs from one ray at a time's.
//   rtcd_bench --benchmark_filter=embree_
#include <embree3/rtcore.h>

#include <cstdio>
#include <cstring>
#include <vector>

#include <benchmark/benchmark.h>

#include "bench_scene.hpp"

namespace {

using namespace rtcd;

constexpr float kExtension = 0.1f;  // the pair's derived extension, a little above 0.1

struct EmbreeScene {
  RTCDevice device = rtcNewDevice(nullptr);
  RTCScene scene = nullptr;

  // The Embree backend's settings: robust traversal, high-quality build.
  explicit EmbreeScene(const Mesh& mesh) {
    scene = rtcNewScene(device);
    rtcSetSceneFlags(scene, RTC_SCENE_FLAG_ROBUST);
    rtcSetSceneBuildQuality(scene, RTC_BUILD_QUALITY_HIGH);
    RTCGeometry g = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_TRIANGLE);
    auto* v = static_cast<float*>(
        rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 3 * sizeof(float), mesh.vertex_count()));
    auto* t = static_cast<uint32_t*>(rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                                                             3 * sizeof(uint32_t), mesh.triangle_count()));
    std::memcpy(v, mesh.positions().data(), mesh.vertex_count() * 3 * sizeof(float));
    std::memcpy(t, mesh.triangles().data(), mesh.triangle_count() * 3 * sizeof(uint32_t));
    rtcCommitGeometry(g);
    rtcAttachGeometry(scene, g);
    rtcReleaseGeometry(g);
    rtcCommitScene(scene);
  }
  ~EmbreeScene() {
    rtcReleaseScene(scene);
    rtcReleaseDevice(device);
  }
  EmbreeScene(const EmbreeScene&) = delete;
  EmbreeScene& operator=(const EmbreeScene&) = delete;
};

RTCRayHit make_ray(const Eigen::Vector3f& origin, const Eigen::Vector3f& direction, float t_max) {
  RTCRayHit r{};
  r.ray.org_x = origin.x();
  r.ray.org_y = origin.y();
  r.ray.org_z = origin.z();
  r.ray.dir_x = direction.x();
  r.ray.dir_y = direction.y();
  r.ray.dir_z = direction.z();
  r.ray.tfar = t_max;
  r.ray.mask = 0xffffffffu;
  r.hit.geomID = RTC_INVALID_GEOMETRY_ID;
  r.hit.primID = RTC_INVALID_GEOMETRY_ID;
  return r;
}

// One direction of the pair: the source's vertices near the target's box,
// placed in the target's frame (the pair differs by a translation only).
void add_rays(const Shape& source, const Shape& target, const Eigen::Vector3f& source_in_target,
              std::vector<RTCRayHit>& rays) {
  const Aabb near = target.bounds().grown(kExtension);
  const RaySources& s = source.sources();
  for (size_t v = 0; v < s.origins.size(); ++v) {
    const Eigen::Vector3f origin = s.origins[v] + source_in_target;
    if (s.directions[v].isZero() || !near.contains(origin.cast<double>())) continue;
    const Eigen::Vector3f d = s.directions[v].normalized();
    rays.push_back(make_ray(origin, d, 3.0e38f));
    rays.push_back(make_ray(origin, -d, kExtension));
  }
}

struct Rays {
  std::vector<RTCRayHit> a_in_b, b_in_a;  // rays traced against b, against a
};

const Rays& pair_rays() {
  static const Rays rays = [] {
    const bench::RestingPair& p = bench::resting_pair();
    Rays r;
    add_rays(*p.a, *p.b, -p.b_offset.cast<float>(), r.a_in_b);
    add_rays(*p.b, *p.a, p.b_offset.cast<float>(), r.b_in_a);
    return r;
  }();
  return rays;
}

enum class Way { single, packet8, stream_incoherent, stream_coherent };

void trace(Way way, RTCScene scene, std::vector<RTCRayHit>& rays) {
  RTCIntersectContext context;
  rtcInitIntersectContext(&context);
  switch (way) {
    case Way::single:
      for (RTCRayHit& r : rays) rtcIntersect1(scene, &context, &r);
      return;
    case Way::stream_incoherent:
    case Way::stream_coherent:
      context.flags =
          way == Way::stream_coherent ? RTC_INTERSECT_CONTEXT_FLAG_COHERENT : RTC_INTERSECT_CONTEXT_FLAG_INCOHERENT;
      rtcIntersect1M(scene, &context, rays.data(), unsigned(rays.size()), sizeof(RTCRayHit));
      return;
    case Way::packet8:
      for (size_t first = 0; first < rays.size(); first += 8) {
        alignas(32) RTCRayHit8 p{};
        alignas(32) int valid[8];
        const size_t n = std::min<size_t>(8, rays.size() - first);
        for (size_t k = 0; k < 8; ++k) {
          valid[k] = k < n ? -1 : 0;
          const RTCRay& r = rays[first + std::min(k, n - 1)].ray;
          p.ray.org_x[k] = r.org_x;
          p.ray.org_y[k] = r.org_y;
          p.ray.org_z[k] = r.org_z;
          p.ray.dir_x[k] = r.dir_x;
          p.ray.dir_y[k] = r.dir_y;
          p.ray.dir_z[k] = r.dir_z;
          p.ray.tfar[k] = r.tfar;
          p.ray.mask[k] = r.mask;
          p.hit.geomID[k] = RTC_INVALID_GEOMETRY_ID;
          p.hit.primID[k] = RTC_INVALID_GEOMETRY_ID;
        }
        rtcIntersect8(valid, scene, &context, &p);
        for (size_t k = 0; k < n; ++k) {
          RTCRayHit& r = rays[first + k];
          r.ray.tfar = p.ray.tfar[k];
          r.hit.geomID = p.hit.geomID[k];
          r.hit.primID = p.hit.primID[k];
        }
      }
      return;
  }
}

void embree_queries(benchmark::State& state, Way way) {
  const bench::RestingPair& p = bench::resting_pair();
  const EmbreeScene a(*p.a->mesh()), b(*p.b->mesh());
  const Rays& rays = pair_rays();
  std::vector<RTCRayHit> to_b = rays.a_in_b, to_a = rays.b_in_a;
  // Hits that differ from one ray at a time's (triangle or distance).
  size_t differing = 0;
  for (const auto& [scene, source] : {std::pair{b.scene, &rays.a_in_b}, std::pair{a.scene, &rays.b_in_a}}) {
    std::vector<RTCRayHit> reference = *source, other = *source;
    trace(Way::single, scene, reference);
    trace(way, scene, other);
    for (size_t k = 0; k < reference.size(); ++k) {
      const bool same = reference[k].hit.primID == other[k].hit.primID && reference[k].ray.tfar == other[k].ray.tfar;
      if (!same && differing++ < 3)
        std::fprintf(stderr, "embree_queries: ray %zu: triangle %d at %.9g one at a time, %d at %.9g here\n", k,
                     int(reference[k].hit.primID), reference[k].ray.tfar, int(other[k].hit.primID), other[k].ray.tfar);
    }
  }
  for (auto _ : state) {
    to_b = rays.a_in_b;
    to_a = rays.b_in_a;
    trace(way, b.scene, to_b);
    trace(way, a.scene, to_a);
    benchmark::DoNotOptimize(to_b.data());
    benchmark::DoNotOptimize(to_a.data());
  }
  const double n = double(rays.a_in_b.size() + rays.b_in_a.size());
  state.counters["rays/step"] = n;
  state.counters["differing hits"] = double(differing);
  state.counters["rays/s"] = benchmark::Counter(n, benchmark::Counter::kIsIterationInvariantRate);
}

BENCHMARK_CAPTURE(embree_queries, single, Way::single)->Unit(benchmark::kMicrosecond);
BENCHMARK_CAPTURE(embree_queries, packet8, Way::packet8)->Unit(benchmark::kMicrosecond);
BENCHMARK_CAPTURE(embree_queries, stream_incoherent, Way::stream_incoherent)->Unit(benchmark::kMicrosecond);
BENCHMARK_CAPTURE(embree_queries, stream_coherent, Way::stream_coherent)->Unit(benchmark::kMicrosecond);

}  // namespace
