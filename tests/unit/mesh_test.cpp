// Mesh validation: each error raised with a message naming the offender,
// and the data derived from a valid mesh.
#include <cmath>
#include <limits>

#include <gtest/gtest.h>

#include "rtcd/error.hpp"
#include "rtcd/mesh_gen.hpp"

namespace {

using rtcd::Mesh;
using rtcd::MeshError;
using rtcd::MeshErrorKind;
using V = std::vector<Eigen::Vector3f>;
using T = std::vector<Mesh::Triangle>;

// A tetrahedron, wound outward.
V tet_positions() { return {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}}; }
T tet_triangles() { return {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}}; }

void expect_error(V p, T t, MeshErrorKind kind, const std::string& fragment, rtcd::MeshOptions o = {}) {
  try {
    Mesh m(std::move(p), std::move(t), o);
    ADD_FAILURE() << "expected " << rtcd::to_string(kind);
  } catch (const MeshError& e) {
    EXPECT_EQ(e.kind(), kind) << e.what();
    EXPECT_NE(std::string(e.what()).find(fragment), std::string::npos) << e.what();
  }
}

TEST(MeshValidation, AcceptsAClosedTetrahedron) {
  const Mesh m(tet_positions(), tet_triangles());
  EXPECT_FALSE(m.report().open());
  for (const auto& n : m.neighbors())
    for (int32_t x : n) EXPECT_GE(x, 0);
}

TEST(MeshValidation, Empty) { expect_error({}, {}, MeshErrorKind::empty, "empty"); }

TEST(MeshValidation, NonFiniteCoordinateNamesTheVertex) {
  V p = tet_positions();
  p[2].y() = std::numeric_limits<float>::quiet_NaN();
  expect_error(p, tet_triangles(), MeshErrorKind::non_finite_coordinate, "vertex 2");
  p[2].y() = std::numeric_limits<float>::infinity();
  expect_error(p, tet_triangles(), MeshErrorKind::non_finite_coordinate, "vertex 2");
}

TEST(MeshValidation, IndexOutOfRangeNamesTheTriangle) {
  T t = tet_triangles();
  t[3][1] = 9;
  expect_error(tet_positions(), t, MeshErrorKind::index_out_of_range, "triangle 3 refers to vertex 9");
}

TEST(MeshValidation, RepeatedVertexNamesTheTriangle) {
  T t = tet_triangles();
  t[1] = {0, 3, 3};
  expect_error(tet_positions(), t, MeshErrorKind::repeated_vertex, "triangle 1 repeats vertex 3");
}

TEST(MeshValidation, ZeroAreaRejectedUnlessAllowed) {
  // A tetrahedron whose apex lies on the base edge's line: two faces collapse.
  V p = tet_positions();
  p[3] = {2, 0, 0};
  expect_error(p, tet_triangles(), MeshErrorKind::zero_area_triangle, "triangle 1 has zero area");
}

TEST(MeshValidation, ZeroAreaKeptAndCountedWhenAllowed) {
  // Vertex 3 moved onto the line through vertices 1 and 2: face (1, 2, 3) is flat.
  V flat = tet_positions();
  flat[3] = {-1, 2, 0};  // on the line x + y = 1 through vertices 1 and 2
  rtcd::MeshOptions allow;
  allow.allow_zero_area = true;
  const Mesh kept(flat, tet_triangles(), allow);
  EXPECT_EQ(kept.report().zero_area_triangles, 1u);
  EXPECT_TRUE(kept.zero_area()[3]);
  EXPECT_EQ(kept.triangle_count(), 4u);
  expect_error(flat, tet_triangles(), MeshErrorKind::zero_area_triangle, "triangle 3");
}

TEST(MeshValidation, NonManifoldEdgeNamesTheThirdTriangle) {
  V p = tet_positions();
  p.push_back({1, 1, 1});
  T t = tet_triangles();
  t.push_back({1, 4, 2});  // a third triangle on edge (1, 2)
  expect_error(p, t, MeshErrorKind::non_manifold_edge, "triangle 4");
}

TEST(MeshValidation, InconsistentWindingNamesTheTriangle) {
  T t = tet_triangles();
  t[2] = {0, 2, 3};  // flipped
  expect_error(tet_positions(), t, MeshErrorKind::inconsistent_winding, "triangle 2");
}

TEST(MeshValidation, InvertedClosedMesh) {
  T t = tet_triangles();
  for (auto& tri : t) std::swap(tri[1], tri[2]);
  expect_error(tet_positions(), t, MeshErrorKind::inverted, "inward");
}

TEST(MeshValidation, UnreferencedVertexKeepsItsIdAndCastsNoRay) {
  V p = tet_positions();
  p.insert(p.begin() + 2, Eigen::Vector3f(5, 5, 5));  // ids 2.. shift by one, as in a file with a stray vertex
  T t = tet_triangles();
  for (auto& tri : t)
    for (uint32_t& i : tri) i += i >= 2;
  const Mesh m(p, t);
  EXPECT_EQ(m.vertex_count(), 5u);
  EXPECT_EQ(m.report().unreferenced_vertices, 1u);
  EXPECT_TRUE(m.vertex_normals()[2].isZero());
  EXPECT_FALSE(m.vertex_normals()[3].isZero());
}

TEST(MeshValidation, CoordinatesBeyondTheSupportedRangeAreRefused) {
  V p = tet_positions();
  for (auto& x : p) x *= 2e12f;
  expect_error(p, tet_triangles(), MeshErrorKind::out_of_range, "vertex 1");
  p = tet_positions();
  for (auto& x : p) x *= 1e12f;  // the edge itself is supported
  EXPECT_NO_THROW(Mesh(p, tet_triangles()));
  p = tet_positions();
  for (auto& x : p) x *= 1e-10f;
  expect_error(p, tet_triangles(), MeshErrorKind::out_of_range, "smallest supported body size");
}

TEST(MeshValidation, WeldJoinsCoincidentVerticesInFirstOccurrenceOrder) {
  // The tetrahedron as a soup: every triangle has its own three corners.
  V soup;
  T t;
  for (const auto& tri : tet_triangles()) {
    t.push_back({uint32_t(soup.size()), uint32_t(soup.size() + 1), uint32_t(soup.size() + 2)});
    for (uint32_t i : tri) soup.push_back(tet_positions()[i]);
  }
  const Mesh unwelded(soup, t);
  EXPECT_EQ(unwelded.vertex_count(), 12u);
  EXPECT_EQ(unwelded.report().boundary_edges, 12u);
  rtcd::MeshOptions weld;
  weld.weld = true;
  const Mesh m(soup, t, weld);
  EXPECT_FALSE(m.report().open());
  const V p = tet_positions();
  EXPECT_EQ(V(m.positions().begin(), m.positions().end()), (V{p[0], p[2], p[1], p[3]}));
  EXPECT_EQ(m.triangles()[0], (Mesh::Triangle{0, 1, 2}));
}

TEST(MeshValidation, OpenMeshAcceptedAndFlagged) {
  const Mesh m = rtcd::gen::open_sheet(4, 1.0, 0.1);
  EXPECT_TRUE(m.report().open());
  EXPECT_EQ(m.report().boundary_edges, 16u);
  int boundary = 0;
  for (const auto& n : m.neighbors())
    for (int32_t x : n) boundary += x == Mesh::no_neighbor;
  EXPECT_EQ(boundary, 16);
}

TEST(MeshDerived, AdjacencyFollowsAlgorithm2Numbering) {
  const Mesh m = rtcd::gen::icosphere(1.0, 1);
  for (size_t t = 0; t < m.triangle_count(); ++t) {
    const auto& tri = m.triangles()[t];
    const std::array<std::array<uint32_t, 2>, 3> edges = {{{tri[2], tri[0]}, {tri[0], tri[1]}, {tri[1], tri[2]}}};
    for (int e = 0; e < 3; ++e) {
      const auto& other = m.triangles()[size_t(m.neighbors()[t][e])];
      int shared = 0;
      for (uint32_t v : other) shared += v == edges[e][0] || v == edges[e][1];
      EXPECT_EQ(shared, 2) << "triangle " << t << " edge " << e;
    }
  }
}

// Convex meshes need no fold check on their walks: closed ones with every
// vertex behind every face, and no other.
TEST(MeshDerived, ConvexOnlyWhenEveryVertexIsBehindEveryFace) {
  EXPECT_TRUE(Mesh(tet_positions(), tet_triangles()).convex());
  EXPECT_TRUE(rtcd::gen::icosphere(1.0, 3).convex());
  EXPECT_TRUE(rtcd::gen::box({0.5, 1.0, 2.0}).convex());
  EXPECT_FALSE(rtcd::gen::torus(1.0, 0.3, 24, 12).convex());
  EXPECT_FALSE(rtcd::gen::concave_blob(902, 1).convex());
  EXPECT_FALSE(rtcd::gen::u_shape().convex());
  EXPECT_FALSE(rtcd::gen::open_sheet(4, 1.0, 0.0).convex()) << "open: a line may cross it once";
}

TEST(MeshDerived, CubeCornerNormalIsTheDiagonalWhateverTheTriangulation) {
  const Mesh m = rtcd::gen::box({0.5, 0.5, 0.5});
  for (size_t v = 0; v < m.vertex_count(); ++v) {
    const Eigen::Vector3f expected = m.positions()[v].normalized();
    EXPECT_NEAR((m.vertex_normals()[v] - expected).norm(), 0.0f, 1e-6f) << "vertex " << v;
  }
  EXPECT_NEAR(m.radius(), std::sqrt(0.75), 1e-6);
  EXPECT_DOUBLE_EQ(m.bounds().max.x(), 0.5);
}

}  // namespace
