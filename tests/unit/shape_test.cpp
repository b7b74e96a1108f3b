// Ray sources of shapes: mesh vertices, icosphere and box corners, sampling.
#include <numbers>
#include <random>
#include <vector>

#include <gtest/gtest.h>

#include "rtcd/error.hpp"
#include "rtcd/mesh_gen.hpp"
#include "rtcd/shape.hpp"

namespace {

TEST(Shape, MeshCastsFromVerticesAlongInwardNormals) {
  const rtcd::Shape s(rtcd::gen::icosphere(2.0, 1));
  ASSERT_EQ(s.sources().origins.size(), 42u);
  for (size_t i = 0; i < 42; ++i)
    EXPECT_NEAR((s.sources().directions[i] + s.sources().origins[i].normalized()).norm(), 0.0f, 1e-5f);
  EXPECT_NEAR(s.radius(), 2.0, 1e-6);
}

TEST(Shape, SphereCastsFromALevel2Icosphere) {
  const rtcd::Shape s(rtcd::Sphere{0.5});
  ASSERT_EQ(s.sources().origins.size(), 162u);
  for (size_t i = 0; i < 162; ++i) {
    EXPECT_NEAR(s.sources().origins[i].norm(), 0.5f, 1e-6f);
    EXPECT_NEAR((s.sources().directions[i] + 2.0f * s.sources().origins[i]).norm(), 0.0f, 1e-5f);
  }
}

TEST(Shape, BoxCastsFromCornersAlongDiagonals) {
  const rtcd::Shape s(rtcd::Box{{1, 2, 3}});
  ASSERT_EQ(s.sources().origins.size(), 8u);
  for (size_t i = 0; i < 8; ++i) {
    const Eigen::Vector3f sign = s.sources().origins[i].cwiseQuotient(Eigen::Vector3f(1, 2, 3));
    EXPECT_NEAR((s.sources().directions[i] + sign / std::sqrt(3.0f)).norm(), 0.0f, 1e-6f);
  }
}

TEST(Shape, SamplingAddsOriginsPerUnitArea) {
  const rtcd::Shape box(rtcd::Box{{0.5, 0.5, 0.5}}, 100.0);  // area 6: about 600 more
  EXPECT_EQ(box.sources().origins.size(), 8u + 600u);
  const rtcd::Shape sphere(rtcd::Sphere{1.0}, 10.0);  // area 4 pi: about 126 more
  EXPECT_EQ(sphere.sources().origins.size(), 162u + 126u);
  for (size_t i = 162; i < sphere.sources().origins.size(); ++i)
    EXPECT_NEAR(sphere.sources().origins[i].norm(), 1.0f, 1e-5f);
}

// The tree over the origins reaches every origin a box holds, each once,
// and turns most others away: boxes of every size around a concave mesh, a
// sampled box (ties on the split axis everywhere) and a sphere's origins.
TEST(Shape, SourceTreeReachesEveryOriginInABoxOnce) {
  const rtcd::Shape shapes[] = {rtcd::Shape(rtcd::gen::concave_blob(902, 3)), rtcd::Shape(rtcd::Box{{1, 1, 1}}, 50.0),
                                rtcd::Shape(rtcd::Sphere{0.5})};
  std::mt19937 rng(7);
  for (const rtcd::Shape& s : shapes) {
    const rtcd::RaySources& rs = s.sources();
    ASSERT_GT(rs.nodes.size(), 1u);
    std::uniform_real_distribution<double> at(-1.2 * s.radius(), 1.2 * s.radius()), size(0.0, 0.3 * s.radius());
    size_t reached = 0, inside = 0;
    for (int trial = 0; trial < 200; ++trial) {
      const Eigen::Vector3d c(at(rng), at(rng), at(rng));
      const rtcd::Aabb box = rtcd::Aabb{c, c}.grown(trial == 0 ? 10 * s.radius() : size(rng));
      std::vector<int> found(rs.item_count(), 0);
      rs.visit_leaves(
          [&](const Eigen::Vector3f& lo, const Eigen::Vector3f& hi) {
            return (hi.cast<double>().array() >= box.min.array()).all() &&
                   (lo.cast<double>().array() <= box.max.array()).all();
          },
          [&](uint32_t n) {
            for (uint32_t v : rs.items_of(n)) ++found[v];
          });
      for (size_t v = 0; v < rs.origins.size(); ++v) {
        ASSERT_LE(found[v], 1) << "origin " << v << ", trial " << trial;
        const bool in = box.contains(rs.origins[v].cast<double>());
        if (in) {
          ASSERT_EQ(found[v], 1) << "origin " << v << ", trial " << trial;
        }
        reached += size_t(found[v]);
        inside += in;
      }
    }
    EXPECT_LT(reached, 3 * inside + 200 * 32) << "the tree should turn most origins outside the boxes away";
  }
}

TEST(Shape, BadVolumesAreRejected) {
  EXPECT_THROW(rtcd::Shape(rtcd::Sphere{-1.0}), rtcd::UsageError);
  EXPECT_THROW(rtcd::Shape(rtcd::Box{{1, 0, 1}}), rtcd::UsageError);
  EXPECT_THROW(rtcd::Shape(rtcd::Sphere{1.0}, -5.0), rtcd::UsageError);
}

}  // namespace
