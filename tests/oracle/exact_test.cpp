// The exact reference on hand-computed cases: cubes, spheres and boxes,
// inside/outside, distances, first hits, and the rays of a cube pair.
#include <cmath>
#include <random>

#include <gtest/gtest.h>

#include "rtcd/mesh_gen.hpp"
#include "rtcd/oracle/exact.hpp"

namespace rtcd::oracle {
namespace {

using Eigen::Vector3d;

std::shared_ptr<const Shape> cube(double h) { return std::make_shared<Shape>(gen::box({h, h, h})); }

TEST(Exact, CubeInsideDistanceAndFirstHit) {
  const ExactShape c(cube(0.5));
  EXPECT_TRUE(c.closed());
  EXPECT_TRUE(c.inside({0, 0, 0}));
  EXPECT_TRUE(c.inside({0.49, 0.49, -0.49}));
  EXPECT_FALSE(c.inside({0.51, 0, 0}));
  EXPECT_FALSE(c.inside({3, -2, 1}));
  EXPECT_NEAR(c.distance({0.3, 0, 0}), 0.2, 1e-12);
  EXPECT_NEAR(c.distance({1, 0, 0}), 0.5, 1e-12);
  EXPECT_NEAR(c.distance({1, 1, 0}), std::sqrt(0.5), 1e-12);
  EXPECT_TRUE(c.within({0.3, 0, 0}, 0.21));
  EXPECT_FALSE(c.within({0.3, 0, 0}, 0.19));

  double t;
  int32_t tri;
  ASSERT_TRUE(c.first_hit({0, 0.1, 0.2}, {1, 0, 0}, t, tri));
  EXPECT_NEAR(t, 0.5, 1e-12);
  const Eigen::Vector3f n = c.shape().mesh()->triangle_normals()[tri];
  EXPECT_NEAR(n.x(), 1.0, 1e-6);  // leaves through the +x face
  ASSERT_TRUE(c.first_hit({2, 0.1, 0.2}, {-1, 0, 0}, t, tri));
  EXPECT_NEAR(t, 1.5, 1e-12);
  EXPECT_FALSE(c.first_hit({2, 0.1, 0.2}, {1, 0, 0}, t, tri));
}

TEST(Exact, VolumesInClosedForm) {
  const ExactShape sphere(std::make_shared<Shape>(Sphere{2.0}));
  EXPECT_TRUE(sphere.inside({1, 1, 1}));
  EXPECT_FALSE(sphere.inside({2, 1, 0}));
  EXPECT_NEAR(sphere.distance({0.5, 0, 0}), 1.5, 1e-12);
  double t;
  int32_t face;
  ASSERT_TRUE(sphere.first_hit({0, 0, 0}, {0, 0, 1}, t, face));
  EXPECT_NEAR(t, 2.0, 1e-12);
  ASSERT_TRUE(sphere.first_hit({0, 0, -5}, {0, 0, 1}, t, face));
  EXPECT_NEAR(t, 3.0, 1e-12);

  const ExactShape box(std::make_shared<Shape>(Box{{1, 2, 3}}));
  EXPECT_TRUE(box.inside({0.9, -1.9, 2.9}));
  EXPECT_FALSE(box.inside({1.1, 0, 0}));
  EXPECT_NEAR(box.distance({0.5, 0, 0}), 0.5, 1e-12);
  EXPECT_NEAR(box.distance({2, 3, 0}), std::sqrt(2.0), 1e-12);
  ASSERT_TRUE(box.first_hit({0, 0, 0}, {0, -1, 0}, t, face));
  EXPECT_NEAR(t, 2.0, 1e-12);
  EXPECT_EQ(face, 3);  // the -y face
}

// A fine icosphere against the sphere it approximates: inside agrees away
// from the chord band, and distances differ by no more than the chord sag.
TEST(Exact, IcosphereAgreesWithItsSphere) {
  const ExactShape mesh(std::make_shared<Shape>(gen::icosphere(1.0, 4)));
  const ExactShape sphere(std::make_shared<Shape>(Sphere{1.0}));
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-1.3, 1.3);
  int inside = 0;
  for (int i = 0; i < 2000; ++i) {
    const Vector3d p(u(rng), u(rng), u(rng));
    if (std::abs(p.norm() - 1.0) < 0.01) continue;
    ASSERT_EQ(mesh.inside(p), sphere.inside(p)) << p.transpose();
    EXPECT_NEAR(mesh.distance(p), sphere.distance(p), 0.01) << p.transpose();
    inside += sphere.inside(p);
  }
  EXPECT_GT(inside, 300);  // both sides were exercised
  EXPECT_LT(inside, 1700);
}

// Cube A (half 0.5) at the origin, cube B (half 0.6) at (1, 0, 0): A's four
// +x vertices are inside B at depth 0.1 * sqrt(3) along their inward
// normals; B's vertices are all outside A.
TEST(Exact, CubePairRays) {
  const auto a = cube(0.5), b = cube(0.6);
  const ExactShape exact_a(a), exact_b(b);
  Pose pose_b;
  pose_b.position = {1, 0, 0};
  const auto ab = exact_b.rays_from(*a, Pose{}, pose_b, 1e-6);
  ASSERT_EQ(ab.size(), 8u);
  int deep = 0;
  for (size_t v = 0; v < ab.size(); ++v) {
    const bool plus_x = a->sources().origins[v].x() > 0;
    EXPECT_EQ(ab[v].deep(), plus_x) << v;
    EXPECT_EQ(ab[v].far_outside(), !plus_x) << v;
    if (plus_x) {
      EXPECT_NEAR(ab[v].depth, 0.1 * std::sqrt(3.0), 1e-7);
    }
    deep += ab[v].deep();
  }
  EXPECT_EQ(deep, 4);
  for (const ExactRay& r : exact_a.rays_from(*b, pose_b, Pose{}, 1e-6)) EXPECT_TRUE(r.far_outside());
}

TEST(Exact, OpenMeshMakesNoInsideClaim) {
  const ExactShape sheet(std::make_shared<Shape>(gen::open_sheet(8, 2.0, 0.1)));
  EXPECT_FALSE(sheet.closed());
  for (const ExactRay& r : sheet.rays_from(*cube(0.5), Pose{}, Pose{}, 1e-6)) EXPECT_FALSE(r.inside);
}

}  // namespace
}  // namespace rtcd::oracle
