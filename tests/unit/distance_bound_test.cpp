// The shapes' distance bounds against the exact distance, brute force over
// every triangle in double: never above it, and near the surface at most a
// few cells below it.
#include <cmath>
#include <limits>
#include <random>

#include <gtest/gtest.h>

#include "rtcd/distance_bound.hpp"
#include "rtcd/mesh_gen.hpp"
#include "rtcd/shape.hpp"

namespace rtcd {
namespace {

double exact_distance(const Mesh& m, const Eigen::Vector3d& p) {
  double best = std::numeric_limits<double>::infinity();
  for (const auto& t : m.triangles()) {
    const Eigen::Vector3d q = closest_on_triangle(p, m.positions()[t[0]].cast<double>(),
                                                  m.positions()[t[1]].cast<double>(),
                                                  m.positions()[t[2]].cast<double>());
    best = std::min(best, (q - p).norm());
  }
  return best;
}

struct Case {
  const char* name;
  Mesh mesh;
};

std::vector<Case> meshes() {
  std::vector<Case> c;
  c.push_back({"blob", gen::concave_blob(900, 3, 0.5)});
  c.push_back({"coarse box", gen::box({1.0, 0.3, 0.05})});
  c.push_back({"thin sheet", gen::open_sheet(12, 2.0, 0.01)});  // open, thinner than a cell
  c.push_back({"knot", gen::torus_knot(2, 3, 1.0, 0.08, 96, 8)});
  c.push_back({"tiny gear", gen::gear(8, 4e-10, 5e-10, 1e-10)});  // kMinBodySize's order
  return c;
}

TEST(DistanceBound, NeverAboveTheExactDistanceAndCloseNearTheSurface) {
  for (Case& c : meshes()) {
    SCOPED_TRACE(c.name);
    const Shape shape(c.mesh);
    const DistanceBound& bound = shape.distance_bound();
    const Aabb box = shape.bounds();
    const double size = (box.max - box.min).norm();
    ASSERT_GT(bound.cell(), 0.0);
    const std::array<int, 3> n = bound.nodes();
    EXPECT_LE(size_t(n[0]) * n[1] * n[2], DistanceBound::max_nodes(c.mesh.triangle_count()));
    EXPECT_GT(size_t(n[0]) * n[1] * n[2], DistanceBound::max_nodes(c.mesh.triangle_count()) / 2);
    EXPECT_EQ(bound.bytes(), size_t(n[0]) * n[1] * n[2] * sizeof(float));
    std::mt19937_64 rng(7);
    std::uniform_real_distribution<double> unit(0.0, 1.0);
    size_t near = 0, tight = 0;
    for (int i = 0; i < 3000; ++i) {
      // Half the points about the surface (a vertex moved a little), half
      // anywhere in the box grown by its size (inside the grid and beyond).
      Eigen::Vector3d p;
      if (i % 2 == 0) {
        const Eigen::Vector3d v = c.mesh.positions()[rng() % c.mesh.vertex_count()].cast<double>();
        p = v + 3.0 * bound.cell() * Eigen::Vector3d(unit(rng) - 0.5, unit(rng) - 0.5, unit(rng) - 0.5);
      } else {
        const Aabb wide = box.grown(size);
        p = wide.min + (wide.max - wide.min).cwiseProduct(Eigen::Vector3d(unit(rng), unit(rng), unit(rng)));
      }
      const double exact = exact_distance(c.mesh, p), lower = bound.lower(p);
      ASSERT_LE(lower, exact * (1 + 1e-12) + 1e-15 * size) << "point " << p.transpose();
      // Within two cells of the surface the exact node distances hold the
      // bound within a cell's diagonal; farther the distance transform's
      // within two of them.
      if (exact < 2.0 * bound.cell()) {
        ++near;
        EXPECT_GE(lower, exact - std::sqrt(3.0) * bound.cell()) << "point " << p.transpose();
        tight += lower >= exact - 0.5 * bound.cell();
      } else if (box.grown(DistanceBound::kPadding * 0.5 * size).contains(p)) {
        EXPECT_GE(lower, exact - 2.0 * std::sqrt(3.0) * bound.cell()) << "point " << p.transpose();
      }
    }
    EXPECT_GT(near, 500u);
    EXPECT_GT(tight, near / 4) << "the bound near the surface is mostly within half a cell";
  }
}

TEST(DistanceBound, VolumesInClosedForm) {
  const Shape sphere(Sphere{2.0}), box(Box{{1.0, 2.0, 3.0}}), ground{HalfSpace{}};
  EXPECT_DOUBLE_EQ(sphere.distance_bound().lower({5, 0, 0}), 3.0);
  EXPECT_DOUBLE_EQ(sphere.distance_bound().lower({0.5, 0, 0}), 1.5);
  EXPECT_DOUBLE_EQ(box.distance_bound().lower({4, 0, 0}), 3.0);
  EXPECT_DOUBLE_EQ(box.distance_bound().lower({0, 0, 2.5}), 0.5) << "inside: the least room";
  EXPECT_DOUBLE_EQ(box.distance_bound().lower({2, 3, 0}), std::sqrt(2.0));
  EXPECT_DOUBLE_EQ(ground.distance_bound().lower({7, -3, 0.25}), 0.25);
  EXPECT_EQ(sphere.distance_bound().bytes(), 0u);
}

// Built once and shared: by every narrow phase and copy of the shape, the
// same object; the same values whatever thread built it.
TEST(DistanceBound, BuiltOnceSharedAndTheSameEveryTime) {
  const Shape shape(gen::concave_blob(900, 5, 1.0));
  const Shape copy = shape;
  EXPECT_EQ(&shape.distance_bound(), &copy.distance_bound());
  const Shape again(gen::concave_blob(900, 5, 1.0));
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> d(-2.0, 2.0);
  for (int i = 0; i < 200; ++i) {
    const Eigen::Vector3d p(d(rng), d(rng), d(rng));
    EXPECT_EQ(shape.distance_bound().lower(p), again.distance_bound().lower(p));
  }
}

}  // namespace
}  // namespace rtcd
