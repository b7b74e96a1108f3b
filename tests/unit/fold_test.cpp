// The fold check's shortcut (kernel/fold.h over Mesh::FoldGuard): it never
// clears a segment that crosses another face, and it clears most short ones.
#include <random>

#include <gtest/gtest.h>

#include "rtcd/kernel/fold.h"
#include "rtcd/mesh_gen.hpp"

namespace {

using Vec = Eigen::Vector3d;

rtcd_vec3 k(const Eigen::Vector3f& v) { return rtcd_v3(v.x(), v.y(), v.z()); }

bool fold_free(const rtcd::Mesh& m, int32_t face, const Eigen::Vector3f& origin, const Eigen::Vector3f& toward,
               float reach) {
  const rtcd::Mesh::FoldGuard& g = m.fold_guard();
  return rtcd_fold_free(face, k(origin), k(toward), reach,
                        reinterpret_cast<const rtcd_vec3*>(m.triangle_normals().data()),
                        reinterpret_cast<const rtcd_fold_face*>(m.fold_guard().faces.data()), g.ring_first.data(),
                        g.ring.data());
}

// Segment ab meets triangle (p0, p1, p2), touching included (double).
bool meets(const Vec& a, const Vec& b, const Vec& p0, const Vec& p1, const Vec& p2) {
  const Vec n = (p1 - p0).cross(p2 - p0);
  const double sa = n.dot(a - p0), sb = n.dot(b - p0);
  if ((sa > 0 && sb > 0) || (sa < 0 && sb < 0) || sa == sb) return false;
  const Vec x = a + (b - a) * (sa / (sa - sb));
  return n.dot((p1 - p0).cross(x - p0)) >= 0 && n.dot((p2 - p1).cross(x - p1)) >= 0 &&
         n.dot((p0 - p2).cross(x - p2)) >= 0;
}

struct Tally {
  int cleared = 0, crossing = 0, trials = 0;
};

// Segments from points well inside random faces into their inner side, of
// lengths up to `longest`: every cleared one is checked against every face.
Tally probe(const rtcd::Mesh& m, double longest, uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::normal_distribution<double> normal;
  std::uniform_int_distribution<size_t> pick(0, m.triangle_count() - 1);
  auto corner = [&](size_t t, int i) { return Vec(m.positions()[m.triangles()[t][size_t(i)]].cast<double>()); };
  Tally tally;
  while (tally.trials < 3000) {
    const size_t f = pick(rng);
    const Vec n = m.triangle_normals()[f].cast<double>();
    if (n.isZero()) continue;
    // A point of f away from its edges, and a direction into its inner side.
    double u = 0.05 + 0.9 * unit(rng), v = 0.05 + 0.9 * unit(rng);
    if (u + v > 0.95) u = 0.95 - u, v = 0.95 - v;
    if (u < 0.05 || v < 0.05) continue;
    const Vec q = corner(f, 0) + u * (corner(f, 1) - corner(f, 0)) + v * (corner(f, 2) - corner(f, 0));
    Vec inward = Vec(normal(rng), normal(rng), normal(rng)).normalized();
    if (inward.dot(n) > -0.2) continue;
    const double length = longest * unit(rng);
    const Eigen::Vector3f origin = (q + length * inward).cast<float>();
    const Eigen::Vector3f toward = (-inward).cast<float>();
    ++tally.trials;
    bool crossing = false;
    for (size_t g = 0; g < m.triangle_count() && !crossing; ++g)
      crossing = g != f && !m.triangle_normals()[g].isZero() &&
                 meets(origin.cast<double>(), q, corner(g, 0), corner(g, 1), corner(g, 2));
    tally.crossing += crossing;
    if (fold_free(m, int32_t(f), origin, toward, float(length))) {
      ++tally.cleared;
      EXPECT_FALSE(crossing) << "triangle " << f << ", length " << length;
    }
  }
  return tally;
}

TEST(FoldGuard, NeverClearsASegmentThatCrossesAnotherFace) {
  // Long segments: many leave the body or cross a fold.
  for (const rtcd::Mesh& m : {rtcd::gen::concave_blob(902, 1), rtcd::gen::torus(1.0, 0.3, 24, 12),
                              rtcd::gen::u_shape(), rtcd::gen::icosphere(1.0, 3)}) {
    const Tally t = probe(m, 2.0 * m.radius(), 7);
    EXPECT_GT(t.crossing, 100);
    EXPECT_GT(t.cleared, 0);
  }
}

TEST(FoldGuard, ClearsMostShallowSegments) {
  // Segments a tenth of a triangle long, the depth of most contacts: the
  // ring's planes and the clearance settle nearly all without a ray.
  for (const rtcd::Mesh& m : {rtcd::gen::concave_blob(902, 2), rtcd::gen::torus(1.0, 0.3, 24, 12),
                              rtcd::gen::box({1.0, 0.2, 0.5})}) {
    double edge = 0;
    for (const auto& t : m.triangles()) edge += (m.positions()[t[1]] - m.positions()[t[0]]).norm();
    edge /= double(m.triangle_count());
    const Tally t = probe(m, 0.1 * edge, 11);
    EXPECT_GT(t.cleared, (t.trials - t.crossing) * 8 / 10);
  }
}

TEST(FoldGuard, FlatNeighboursAreNotInTheRing) {
  // A box's faces are flat: a triangle's coplanar neighbours cannot meet a
  // segment into its inner side, so only the side faces' triangles remain.
  const rtcd::Mesh m = rtcd::gen::box({1.0, 1.0, 1.0});
  const rtcd::Mesh::FoldGuard& g = m.fold_guard();
  for (uint32_t f = 0; f < m.triangle_count(); ++f) {
    // Every triangle touches two or three side faces at its corners.
    EXPECT_GE(g.ring_first[f + 1] - g.ring_first[f], 2u) << "triangle " << f << ": its side faces are not in its ring";
    for (uint32_t k = g.ring_first[f]; k < g.ring_first[f + 1]; ++k) {
      const int32_t other = g.ring[k];
      EXPECT_LT(m.triangle_normals()[f].dot(m.triangle_normals()[size_t(other)]), 0.5f) << f << " " << other;
    }
  }
}

TEST(FoldGuard, SmallFacesFarApartNeedFewCells) {
  // Two millimetre triangles near the origin and one far out: a grid of
  // their mean size would need 1e19 cells; it is coarsened to a few.
  const float far = 9e11f, size = 1e6f;
  const rtcd::Mesh m({{0, 0, 0}, {1e-3f, 0, 0}, {0, 1e-3f, 0}, {0, 0, 1}, {1e-3f, 0, 1}, {0, 1e-3f, 1},
                      {far, far, far}, {far + size, far, far}, {far, far + size, far}},
                     {{0, 1, 2}, {3, 4, 5}, {6, 7, 8}});
  const rtcd::Mesh::FoldGuard& g = m.fold_guard();
  ASSERT_EQ(g.faces.size(), 3u);
  for (const auto& f : g.faces) EXPECT_GE(f.clearance, 0.0f);
  EXPECT_EQ(g.ring.size(), 0u);  // no two share a vertex
}

TEST(FoldGuard, OnlyZeroAreaTrianglesLeaveNothingToGuard) {
  // The body's size comes from a vertex no triangle uses; the one triangle
  // (kept with allow_zero_area) is a point: no face to size a grid by
  // (mesh_file fuzzer).
  rtcd::MeshOptions options;
  options.allow_zero_area = true;
  const rtcd::Mesh m({{0, 0, 0}, {0, 0, 0}, {0, 0, 0}, {1, 1, 1}}, {{0, 1, 2}}, options);
  ASSERT_EQ(m.fold_guard().faces.size(), 1u);
  EXPECT_EQ(m.fold_guard().faces[0].clearance, 0.0f);
  EXPECT_TRUE(m.fold_guard().ring.empty());
}

}  // namespace
