// The walk of Algorithm 1: convergence, traps, shared edges and vertices.
#include <random>

#include <gtest/gtest.h>

#include "rtcd/kernel/walk.h"
#include "rtcd/mesh_gen.hpp"

namespace {

rtcd_vec3 k(const Eigen::Vector3f& v) { return rtcd_v3(v.x(), v.y(), v.z()); }

rtcd_walk_result walk(const rtcd::Mesh& m, const rtcd_ray& ray, int32_t start, uint32_t max_steps) {
  return rtcd_walk(&ray, reinterpret_cast<const rtcd_vec3*>(m.positions().data()),
                   reinterpret_cast<const rtcd_uint*>(m.triangles().data()),
                   reinterpret_cast<const rtcd_int*>(m.neighbors().data()), m.zero_area().data(), start, max_steps);
}

// The triangle the ray leaves the mesh through, by brute force.
int32_t exit_triangle(const rtcd::Mesh& m, const rtcd_ray& ray) {
  for (size_t t = 0; t < m.triangle_count(); ++t) {
    const auto& tri = m.triangles()[t];
    const rtcd_location loc =
        rtcd_locate(&ray, k(m.positions()[tri[0]]), k(m.positions()[tri[1]]), k(m.positions()[tri[2]]));
    if (loc.inside && loc.facing > 0) return int32_t(t);
  }
  return -1;
}

TEST(Walk, FromAWrongTriangleOfAConvexMeshReachesTheRightOne) {
  const rtcd::Mesh m = rtcd::gen::icosphere(1.0, 3);
  std::mt19937 g(3);
  std::normal_distribution<float> n;
  std::uniform_int_distribution<size_t> pick(0, m.triangle_count() - 1);
  for (int i = 0; i < 500; ++i) {
    const Eigen::Vector3f d = Eigen::Vector3f(n(g), n(g), n(g)).normalized();
    const Eigen::Vector3f o = 0.5f * Eigen::Vector3f(n(g), n(g), n(g)).normalized();
    const rtcd_ray ray = rtcd_make_ray(k(o), k(d));
    // Any start on the half the ray leaves through.
    size_t start;
    do start = pick(g);
    while (m.triangle_normals()[start].dot(d) < 0.2f);
    const rtcd_walk_result w = walk(m, ray, int32_t(start), 1000);
    ASSERT_EQ(w.status, RTCD_LINE_HIT) << "i=" << i;
    EXPECT_EQ(w.triangle, exit_triangle(m, ray)) << "i=" << i;
    EXPECT_LE(w.steps, 64u);
  }
}

TEST(Walk, ThroughASharedEdgeOrVertexNeverLostNeverOscillates) {
  const rtcd::Mesh m = rtcd::gen::icosphere(1.0, 2);
  std::mt19937 g(5);
  std::uniform_real_distribution<float> u(0, 1);
  for (size_t t = 0; t < m.triangle_count(); ++t) {
    const auto& tri = m.triangles()[t];
    for (int e = 0; e < 3; ++e) {
      const Eigen::Vector3f a = m.positions()[tri[(e + 2) % 3]], b = m.positions()[tri[e]];
      for (float w : {0.0f, u(g)}) {  // the shared vertex a, then a point on the shared edge
        const Eigen::Vector3f target = a + w * (b - a);
        const Eigen::Vector3f o = 0.3f * target;  // inside, aimed through the point
        const rtcd_ray ray = rtcd_make_ray(k(o), k((target - o).normalized()));
        // From this triangle and from the one across the edge alike.
        for (int32_t start : {int32_t(t), m.neighbors()[t][e]}) {
          const rtcd_walk_result r = walk(m, ray, start, 100);
          ASSERT_EQ(r.status, RTCD_LINE_HIT) << "triangle " << t << " edge " << e << " w " << w;
          EXPECT_LE(r.steps, 8u) << "oscillation: triangle " << t << " edge " << e;
          EXPECT_NEAR(r.t, (target - o).norm(), 1e-5f);
        }
      }
    }
  }
}

// A concave body: walks from wrong starts end with an explicit status and
// never run past the step limit; some are trapped (a loop) and say so.
TEST(Walk, ConcaveTrapEndsAtTheStepLimit) {
  const rtcd::Mesh m = rtcd::gen::torus(1.0, 0.35, 48, 24);
  std::mt19937 g(9);
  std::normal_distribution<float> n;
  std::uniform_int_distribution<size_t> pick(0, m.triangle_count() - 1);
  // More steps than triangles: a walk that reaches the limit has revisited a
  // triangle, so it was in a loop.
  const uint32_t limit = uint32_t(2 * m.triangle_count());
  int trapped = 0, hits = 0;
  for (int i = 0; i < 3000; ++i) {
    const Eigen::Vector3f o = Eigen::Vector3f(n(g), n(g), 0.3f * n(g));
    const rtcd_ray ray = rtcd_make_ray(k(o), k(Eigen::Vector3f(n(g), n(g), n(g)).normalized()));
    const rtcd_walk_result r = walk(m, ray, int32_t(pick(g)), limit);
    ASSERT_LE(r.steps, limit);
    ASSERT_GE(r.status, RTCD_LINE_HIT);
    ASSERT_LT(r.status, RTCD_LINE_STATUS_COUNT);
    if (r.status == RTCD_LINE_STEP_LIMIT) {
      EXPECT_EQ(r.steps, limit);
      ++trapped;
    }
    hits += r.status == RTCD_LINE_HIT;
  }
  EXPECT_GT(trapped, 0) << "no trap found: the test would be vacuous";
  EXPECT_GT(hits, 0);
}

// A kept zero-area triangle is never hit: the walk stops on it as PARALLEL.
// (The flag, not the geometry, decides: a sliver may still have det != 0.)
TEST(Walk, FlaggedZeroAreaTriangleIsNeverHit) {
  const rtcd::Mesh m = rtcd::gen::icosphere(1.0, 2);
  const rtcd_ray ray = rtcd_make_ray(rtcd_v3(0.1f, 0.05f, 0.0f), rtcd_v3(0.0f, 0.0f, 1.0f));
  const int32_t target = exit_triangle(m, ray);
  ASSERT_GE(target, 0);
  ASSERT_EQ(walk(m, ray, target, 10).status, RTCD_LINE_HIT);
  std::vector<uint8_t> flags(m.triangle_count(), 0);
  flags[size_t(target)] = 1;
  const rtcd_walk_result r =
      rtcd_walk(&ray, reinterpret_cast<const rtcd_vec3*>(m.positions().data()),
                reinterpret_cast<const rtcd_uint*>(m.triangles().data()),
                reinterpret_cast<const rtcd_int*>(m.neighbors().data()), flags.data(), target, 10);
  EXPECT_EQ(r.status, RTCD_LINE_PARALLEL);
}

TEST(Walk, BoundaryEdgeOfAnOpenMeshEndsTheWalk) {
  const rtcd::Mesh m = rtcd::gen::open_sheet(8, 2.0, 0.0);
  // Straight down beside the sheet, starting from a corner triangle.
  const rtcd_ray ray = rtcd_make_ray(rtcd_v3(5, 0, 1), rtcd_v3(0, 0, -1));
  const rtcd_walk_result r = walk(m, ray, 0, 100);
  EXPECT_EQ(r.status, RTCD_LINE_BOUNDARY);
}

TEST(Walk, BehindAndFrontCrossings) {
  const rtcd::Mesh m = rtcd::gen::box({0.5, 0.5, 0.5});
  // Outside beyond +x, looking further out: the +x face is behind it.
  rtcd_ray ray = rtcd_make_ray(rtcd_v3(0.7f, 0.1f, 0.1f), rtcd_v3(1, 0, 0));
  int32_t plus_x = -1;
  for (size_t t = 0; t < m.triangle_count(); ++t)
    if (m.triangle_normals()[t].x() > 0.9f) plus_x = int32_t(t);
  rtcd_walk_result r = walk(m, ray, plus_x, 10);
  EXPECT_EQ(r.status, RTCD_LINE_BEHIND);
  EXPECT_NEAR(r.t, -0.2f, 1e-6f);
  // Outside beyond -x, looking at the box: the -x face is entered.
  ray = rtcd_make_ray(rtcd_v3(-0.7f, 0.1f, 0.1f), rtcd_v3(1, 0, 0));
  int32_t minus_x = -1;
  for (size_t t = 0; t < m.triangle_count(); ++t)
    if (m.triangle_normals()[t].x() < -0.9f) minus_x = int32_t(t);
  r = walk(m, ray, minus_x, 10);
  EXPECT_EQ(r.status, RTCD_LINE_FRONT);
}

}  // namespace
