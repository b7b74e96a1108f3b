// The committed meshes are exactly what their generators make, and have the
// counts and topology the thesis' scenes call for.
#include <set>

#include <gtest/gtest.h>

#include "meshes.hpp"

namespace {

TEST(Data, CommittedMeshesMatchTheirGenerators) {
  for (const auto& recipe : rtcd::data::committed_meshes()) {
    const rtcd::Mesh made = recipe.make();
    const rtcd::Mesh file = rtcd::Mesh::load(std::string(RTCD_DATA_DIR) + "/meshes/" + recipe.file);
    ASSERT_EQ(file.vertex_count(), made.vertex_count()) << recipe.file;
    ASSERT_EQ(file.triangle_count(), made.triangle_count()) << recipe.file;
    for (size_t v = 0; v < made.vertex_count(); ++v) ASSERT_EQ(file.positions()[v], made.positions()[v]) << recipe.file;
    for (size_t t = 0; t < made.triangle_count(); ++t)
      ASSERT_EQ(file.triangles()[t], made.triangles()[t]) << recipe.file;
  }
}

// Some vertex lies strictly outside the plane of some triangle: not convex.
bool concave(const rtcd::Mesh& m) {
  for (size_t t = 0; t < m.triangle_count(); ++t) {
    const Eigen::Vector3f& n = m.triangle_normals()[t];
    const Eigen::Vector3f& p = m.positions()[m.triangles()[t][0]];
    for (const auto& q : m.positions())
      if (n.dot(q - p) > 1e-3f) return true;
  }
  return false;
}

TEST(Data, ConcaveClassAndStreamSet) {
  const std::map<std::string, size_t> expected = {
      {"blob_902.obj", 902}, {"stream_902.obj", 902}, {"stream_2130.obj", 2130},
      {"stream_3456.obj", 3456}, {"stream_3458.obj", 3458}};
  for (const auto& [file, triangles] : expected) {
    const rtcd::Mesh m = rtcd::Mesh::load(std::string(RTCD_DATA_DIR) + "/meshes/" + file);
    EXPECT_EQ(m.triangle_count(), triangles) << file;
    EXPECT_EQ(m.vertex_count(), triangles / 2 + 2) << file;  // closed genus 0: V - E + F = 2
    EXPECT_FALSE(m.report().open()) << file;
    EXPECT_TRUE(concave(m)) << file;
  }
  const rtcd::Mesh thesis = rtcd::Mesh::load(std::string(RTCD_DATA_DIR) + "/meshes/blob_902.obj");
  EXPECT_EQ(thesis.vertex_count(), 453u);
}

}  // namespace
