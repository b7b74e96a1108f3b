// The per-pair limits derived from the scene (rtcd/limits.hpp).
#include <gtest/gtest.h>

#include "rtcd/limits.hpp"
#include "rtcd/mesh_gen.hpp"

namespace {

using rtcd::Config;
using rtcd::derive_limits;
using rtcd::measure_scale;
using rtcd::Shape;

Shape scaled_box(double s, double thin) { return Shape(rtcd::gen::box({s, s, thin * s})); }

TEST(Limits, ThicknessIsTheInwardSelfRayLength) {
  // A box's vertex rays run along the corner diagonals: across the thin
  // side they leave after thickness * sqrt(3) (normals weighted by angle).
  const rtcd::ShapeScale plate = measure_scale(scaled_box(1.0, 0.02));
  EXPECT_NEAR(plate.thickness, 0.04 * std::sqrt(3.0), 1e-6);
  EXPECT_EQ(plate.triangles, 12u);
  const rtcd::ShapeScale sphere = measure_scale(Shape(rtcd::Sphere{0.5}));
  EXPECT_DOUBLE_EQ(sphere.thickness, 1.0);
  EXPECT_FALSE(std::isfinite(measure_scale(Shape(rtcd::HalfSpace{})).thickness));
}

TEST(Limits, FollowTheShapesScale) {
  const auto blob = rtcd::gen::concave_blob(902, 3, 1.0);
  std::vector<Eigen::Vector3f> p;
  for (const auto& v : blob.positions()) p.push_back(v * 8.0f);  // a power of two: exact
  const Shape small(blob), large(rtcd::Mesh(p, {blob.triangles().begin(), blob.triangles().end()}));
  const Config derived;
  const auto a = derive_limits(derived, measure_scale(small), measure_scale(small), 0.01);
  const auto b = derive_limits(derived, measure_scale(large), measure_scale(large), 0.08);
  EXPECT_NEAR(b.distance_extension, 8 * a.distance_extension, 1e-9 * b.distance_extension);
  EXPECT_NEAR(b.displacement_threshold, 8 * a.displacement_threshold, 1e-9 * b.displacement_threshold);
  EXPECT_EQ(a.max_walk_steps, b.max_walk_steps);
}

TEST(Limits, ThinBodiesLowerTheThresholdAndSpeedRaisesTheExtension) {
  const auto thick = measure_scale(scaled_box(1.0, 1.0)), thin = measure_scale(scaled_box(1.0, 0.02));
  const Config derived;
  const auto resting = derive_limits(derived, thick, thin, 0.0);
  EXPECT_DOUBLE_EQ(resting.distance_extension, rtcd::resting_extension(std::min(thick.radius, thin.radius)));
  EXPECT_DOUBLE_EQ(resting.displacement_threshold, std::min(resting.distance_extension / 2, thin.thickness / 4));
  const auto fast = derive_limits(derived, thick, thin, 0.5);
  EXPECT_DOUBLE_EQ(fast.distance_extension, 1.0);
  // No farther than the smaller body's size, however fast.
  EXPECT_DOUBLE_EQ(derive_limits(derived, thick, thin, 1e3).distance_extension, std::min(thick.radius, thin.radius));
  // Symmetric: numbering the bodies the other way changes nothing.
  const auto swapped = derive_limits(derived, thin, thick, 0.5);
  EXPECT_EQ(swapped.distance_extension, fast.distance_extension);
  EXPECT_EQ(swapped.displacement_threshold, fast.displacement_threshold);
  EXPECT_EQ(swapped.max_walk_steps, fast.max_walk_steps);
}

TEST(Limits, WalkLimitCoversTheMotionInTrianglesUpToTheTriangleCount) {
  const Shape fine(rtcd::gen::icosphere(1.0, 4));  // 5120 triangles
  const auto s = measure_scale(fine);
  const Config derived;
  EXPECT_EQ(derive_limits(derived, s, s, 0.0).max_walk_steps, 32u);
  const auto moving = derive_limits(derived, s, s, 0.5);
  EXPECT_EQ(moving.max_walk_steps, uint32_t(std::ceil(4 * 2 * 0.5 / s.edge)));
  EXPECT_EQ(derive_limits(derived, s, s, 1e6).max_walk_steps, s.triangles);
}

TEST(Limits, AValueSetInTheConfigWinsAndTheThresholdStaysWithinTheExtension) {
  const auto a = measure_scale(scaled_box(1.0, 1.0));
  Config c;
  c.displacement_threshold = 5.0;  // above the derived extension: the extension follows it
  auto l = derive_limits(c, a, a, 0.0);
  EXPECT_EQ(l.displacement_threshold, 5.0);
  EXPECT_EQ(l.distance_extension, 5.0);
  c = {};
  c.distance_extension = 1e-3;  // the threshold follows it: half of it
  l = derive_limits(c, a, a, 0.0);
  EXPECT_EQ(l.distance_extension, 1e-3);
  EXPECT_EQ(l.displacement_threshold, 0.5e-3);
  c.max_walk_steps = 7;
  EXPECT_EQ(derive_limits(c, a, a, 10.0).max_walk_steps, 7u);
}

}  // namespace
