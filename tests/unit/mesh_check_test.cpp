// The mesh checker: each defect class on a small committed mesh, and the
// self-intersection search against an all-pairs search.
#include <map>
#include <random>

#include <gtest/gtest.h>

#include "rtcd/mesh_check.hpp"
#include "rtcd/mesh_gen.hpp"

namespace {

const std::string defects = std::string(RTCD_DATA_DIR) + "/defects/";

rtcd::MeshCheck check_file(const std::string& path) {
  const rtcd::MeshData d = rtcd::read_mesh_file(path);
  return rtcd::check_mesh(d.positions, d.triangles);
}

// Every finding but `expected` has a count of zero.
void expect_only(const rtcd::MeshCheck& c, const std::map<std::string, size_t>& expected) {
  for (const auto& f : c.findings) {
    const auto it = expected.find(f.name);
    EXPECT_EQ(f.count, it == expected.end() ? 0u : it->second) << f.name;
  }
}

TEST(MeshCheck, CommittedConcaveMeshIsFit) {
  const auto c = check_file(std::string(RTCD_DATA_DIR) + "/meshes/blob_902.obj");
  EXPECT_TRUE(c.fit());
  EXPECT_EQ(c.vertices, 453u);
  EXPECT_EQ(c.triangles, 902u);
  EXPECT_EQ(c.components, 1u);
  EXPECT_TRUE(c.closed);
  EXPECT_GT(c.signed_volume, 0);
  expect_only(c, {});
}

TEST(MeshCheck, TwoOverlappingCubesInOneFileCrossThemselves) {
  const auto c = check_file(defects + "two_cubes_overlapping.off");
  EXPECT_FALSE(c.fit());
  EXPECT_EQ(c.components, 2u);
  EXPECT_TRUE(c.closed);
  // Cube B's faces x, y, z = 0.5 each cross two faces of cube A (x, y, z = 1).
  expect_only(c, {{"self_intersections", 6}});
  for (const auto& pair : c.finding("self_intersections").examples) {
    EXPECT_LT(pair[0], 12u);  // one triangle of each cube
    EXPECT_GE(pair[1], 12u);
  }
}

TEST(MeshCheck, PinchVerticesAreFit) {
  const auto shared = check_file(defects + "pinch_shared.off");
  EXPECT_TRUE(shared.fit());
  expect_only(shared, {{"pinch_vertices", 1}});
  EXPECT_EQ(shared.finding("pinch_vertices").examples[0], std::vector<uint32_t>{0});
  const auto split = check_file(defects + "pinch_split.off");
  EXPECT_TRUE(split.fit());
  EXPECT_EQ(split.components, 2u);
  expect_only(split, {{"coincident_vertices", 1}});
  EXPECT_EQ(split.finding("coincident_vertices").examples[0], (std::vector<uint32_t>{0, 4}));
}

TEST(MeshCheck, FlippedTriangleDisagreesWithItsThreeNeighbours) {
  const auto c = check_file(defects + "flipped_triangle.off");
  EXPECT_FALSE(c.fit());
  expect_only(c, {{"inconsistent_orientation", 3}});
  for (const auto& pair : c.finding("inconsistent_orientation").examples)
    EXPECT_TRUE(pair[0] == 4 || pair[1] == 4);
}

TEST(MeshCheck, OpenSheetHasBoundaryEdges) {
  const auto c = check_file(std::string(RTCD_DATA_DIR) + "/meshes/open_sheet.obj");
  EXPECT_FALSE(c.fit());
  EXPECT_FALSE(c.closed);
  expect_only(c, {{"boundary_edges", 64}});
}

TEST(MeshCheck, NonManifoldEdgeInvertedAndOutOfRange) {
  const auto fin = check_file(defects + "non_manifold_edge.off");
  EXPECT_FALSE(fin.fit());
  EXPECT_EQ(fin.finding("non_manifold_edges").count, 1u);
  EXPECT_EQ(fin.finding("non_manifold_edges").examples[0], (std::vector<uint32_t>{0, 1}));
  const auto inverted = check_file(defects + "inverted_cube.off");
  expect_only(inverted, {{"inverted", 1}});
  EXPECT_LT(inverted.signed_volume, 0);
  const auto huge = check_file(defects + "huge_cube.off");
  expect_only(huge, {{"out_of_range", 8}});
  EXPECT_FALSE(huge.fit());
}

TEST(MeshCheck, SliversZeroAreaAndUnreferencedAreNotesOnly) {
  const auto sliver = check_file(defects + "sliver_tetrahedron.off");
  EXPECT_TRUE(sliver.fit());
  expect_only(sliver, {{"sliver_triangles", 1}});
  // A zero-area triangle (vertex 3 lies on the edge 0-1) and a stray vertex 4.
  const std::vector<Eigen::Vector3f> p = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0.5f, 0, 0}, {7, 7, 7}};
  const std::vector<rtcd::Mesh::Triangle> t = {{0, 1, 2}, {0, 3, 1}};
  const auto c = rtcd::check_mesh(p, t);
  EXPECT_EQ(c.finding("zero_area_triangles").count, 1u);
  EXPECT_EQ(c.finding("zero_area_triangles").examples[0], std::vector<uint32_t>{1});
  EXPECT_EQ(c.finding("unreferenced_vertices").examples[0], std::vector<uint32_t>{4});
  EXPECT_FALSE(c.finding("zero_area_triangles").defect);
  EXPECT_FALSE(c.finding("unreferenced_vertices").defect);
}

TEST(MeshCheck, SelfIntersectionSearchMatchesAllPairs) {
  // Random triangles in a unit box: the tree must find exactly the pairs an
  // all-pairs loop over the same test finds, which is every crossing pair of
  // a two-triangle mesh.
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> u(0, 1);
  std::vector<Eigen::Vector3f> p;
  std::vector<rtcd::Mesh::Triangle> t;
  for (uint32_t i = 0; i < 120; ++i) {
    const Eigen::Vector3f c(u(rng), u(rng), u(rng));
    for (int k = 0; k < 3; ++k) p.push_back(c + 0.5f * Eigen::Vector3f(u(rng) - 0.5f, u(rng) - 0.5f, u(rng) - 0.5f));
    t.push_back({3 * i, 3 * i + 1, 3 * i + 2});
  }
  const auto found = rtcd::self_intersections(p, t);
  std::vector<std::array<uint32_t, 2>> brute;
  for (uint32_t i = 0; i < t.size(); ++i)
    for (uint32_t j = i + 1; j < t.size(); ++j) {
      const std::vector<Eigen::Vector3f> q = {p[t[i][0]], p[t[i][1]], p[t[i][2]], p[t[j][0]], p[t[j][1]], p[t[j][2]]};
      const std::vector<rtcd::Mesh::Triangle> two = {{0, 1, 2}, {3, 4, 5}};
      if (!rtcd::self_intersections(q, two).empty()) brute.push_back({i, j});
    }
  EXPECT_GT(brute.size(), 20u);  // the test has crossings to find
  EXPECT_EQ(found, brute);
}

TEST(MeshCheck, TouchingIsNotCrossing) {
  // Two tetrahedra sharing only a position (pinch) or an edge at a dihedral
  // angle do not cross; pushing one through the other does.
  const rtcd::MeshData d = rtcd::read_mesh_file(defects + "pinch_split.off");
  EXPECT_TRUE(rtcd::self_intersections(d.positions, d.triangles).empty());
  auto moved = d.positions;
  for (size_t v = 4; v < 8; ++v) moved[v] += Eigen::Vector3f(0.2f, 0.2f, 0.2f);
  EXPECT_FALSE(rtcd::self_intersections(moved, d.triangles).empty());
}

}  // namespace
