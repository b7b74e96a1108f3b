// MeshTracer::nearest with a bound (`enough`): Embree's search may stop at
// the first triangle within it, the basic tracer always finds the nearest.
// Their answers must agree on what the callers read from them: a triangle
// within the bound whenever the nearest is, and otherwise the very nearest.
#include <gtest/gtest.h>

#include <random>

#include "basic/basic_backend.hpp"
#include "embree/embree_backend.hpp"
#include "rtcd/kernel/nearest.h"
#include "rtcd/mesh_gen.hpp"

namespace {

float distance2(const rtcd::Mesh& mesh, int32_t triangle, const rtcd_vec3& p) {
  auto v = [&](uint32_t i) {
    const Eigen::Vector3f& q = mesh.positions()[i];
    return rtcd_v3(q.x(), q.y(), q.z());
  };
  const auto& t = mesh.triangles()[size_t(triangle)];
  return rtcd_point_triangle_distance2(p, v(t[0]), v(t[1]), v(t[2]));
}

TEST(TracerNearest, EmbreeStopsWithinTheBoundAndOtherwiseFindsTheNearest) {
  const rtcd::Mesh mesh = rtcd::gen::concave_blob(2000, 7);
  const auto embree = rtcd::make_embree_tracers()->build(mesh);
  const auto basic = rtcd::make_basic_tracers()->build(mesh);
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> coordinate(-1.3f, 1.3f), bound(0.0f, 0.2f);
  int stopped_early = 0, beyond_the_bound = 0;
  for (int i = 0; i < 2000; ++i) {
    const rtcd_vec3 p = rtcd_v3(coordinate(rng), coordinate(rng), coordinate(rng));
    const float radius = 0.5f, enough = bound(rng);
    const int32_t nearest = basic->nearest(p, radius, 0.0f);
    ASSERT_EQ(embree->nearest(p, radius, 0.0f), nearest) << "no bound: the nearest, by the tie rule";
    const int32_t found = embree->nearest(p, radius, enough);
    if (nearest < 0) {
      EXPECT_EQ(found, -1);
      continue;
    }
    ASSERT_GE(found, 0);
    const float best = distance2(mesh, nearest, p);
    if (best <= enough * enough) {
      EXPECT_LE(distance2(mesh, found, p), enough * enough) << "a triangle within the bound";
      stopped_early += found != nearest;
    } else {
      EXPECT_EQ(found, nearest) << "none within the bound: the nearest";
      ++beyond_the_bound;
    }
  }
  // Both cases were met, and the bound did end some searches early.
  EXPECT_GT(stopped_early, 0);
  EXPECT_GT(beyond_the_bound, 100);
}

}  // namespace
