// Loading OBJ, OFF, PLY and STL through assimp, and file errors.
#include <filesystem>
#include <fstream>

#include <gtest/gtest.h>

#include "rtcd/error.hpp"
#include "rtcd/mesh_gen.hpp"

namespace {

namespace fs = std::filesystem;

class MeshFiles : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("rtcd_mesh_io_" + std::to_string(::getpid()));
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  fs::path write(const std::string& name, const std::string& text) {
    std::ofstream(dir_ / name) << text;
    return dir_ / name;
  }
  fs::path dir_;
  const rtcd::Mesh box_ = rtcd::gen::box({0.5, 0.5, 0.5});
};

std::string off_text(const rtcd::Mesh& m) {
  std::ostringstream s;
  s << "OFF\n" << m.vertex_count() << ' ' << m.triangle_count() << " 0\n";
  for (const auto& p : m.positions()) s << p.x() << ' ' << p.y() << ' ' << p.z() << '\n';
  for (const auto& t : m.triangles()) s << "3 " << t[0] << ' ' << t[1] << ' ' << t[2] << '\n';
  return s.str();
}

std::string ply_text(const rtcd::Mesh& m) {
  std::ostringstream s;
  s << "ply\nformat ascii 1.0\nelement vertex " << m.vertex_count()
    << "\nproperty float x\nproperty float y\nproperty float z\nelement face " << m.triangle_count()
    << "\nproperty list uchar int vertex_indices\nend_header\n";
  for (const auto& p : m.positions()) s << p.x() << ' ' << p.y() << ' ' << p.z() << '\n';
  for (const auto& t : m.triangles()) s << "3 " << t[0] << ' ' << t[1] << ' ' << t[2] << '\n';
  return s.str();
}

std::string stl_text(const rtcd::Mesh& m) {
  std::ostringstream s;
  s << "solid box\n";
  for (size_t i = 0; i < m.triangle_count(); ++i) {
    const auto& n = m.triangle_normals()[i];
    s << " facet normal " << n.x() << ' ' << n.y() << ' ' << n.z() << "\n  outer loop\n";
    for (uint32_t v : m.triangles()[i]) {
      const auto& p = m.positions()[v];
      s << "   vertex " << p.x() << ' ' << p.y() << ' ' << p.z() << '\n';
    }
    s << "  endloop\n endfacet\n";
  }
  s << "endsolid box\n";
  return s.str();
}

void expect_box(const rtcd::Mesh& m) {
  EXPECT_EQ(m.vertex_count(), 8u);
  EXPECT_EQ(m.triangle_count(), 12u);
  EXPECT_FALSE(m.report().open());
  EXPECT_NEAR(m.radius(), std::sqrt(0.75), 1e-6);
}

TEST_F(MeshFiles, ObjRoundTripIsExact) {
  const rtcd::Mesh blob = rtcd::gen::concave_blob(200, 9);
  rtcd::save_obj(blob, dir_ / "blob.obj");
  const rtcd::Mesh back = rtcd::Mesh::load(dir_ / "blob.obj");
  ASSERT_EQ(back.vertex_count(), blob.vertex_count());
  for (size_t v = 0; v < blob.vertex_count(); ++v) EXPECT_EQ(back.positions()[v], blob.positions()[v]);
  for (size_t t = 0; t < blob.triangle_count(); ++t) EXPECT_EQ(back.triangles()[t], blob.triangles()[t]);
}

TEST_F(MeshFiles, Off) { expect_box(rtcd::Mesh::load(write("box.off", off_text(box_)))); }
TEST_F(MeshFiles, Ply) { expect_box(rtcd::Mesh::load(write("box.ply", ply_text(box_)))); }
TEST_F(MeshFiles, StlWeldsCorners) { expect_box(rtcd::Mesh::load(write("box.stl", stl_text(box_)))); }

void expect_file_error(const fs::path& path, const std::string& fragment) {
  try {
    rtcd::Mesh::load(path);
    ADD_FAILURE() << "expected a file error for " << path;
  } catch (const rtcd::MeshError& e) {
    EXPECT_NE(std::string(e.what()).find(fragment), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find(path.filename().string()), std::string::npos) << e.what();
  }
}

TEST_F(MeshFiles, MissingFile) { expect_file_error(dir_ / "nope.obj", "no such file"); }
TEST_F(MeshFiles, UnsupportedExtension) { expect_file_error(write("box.xyz", "1 2 3"), "unsupported"); }
TEST_F(MeshFiles, GarbageContent) { expect_file_error(write("bad.off", "this is not a mesh\n"), "bad.off"); }

// Files that crash or hang assimp 5.2 are rejected before it reads them.
TEST_F(MeshFiles, OffLinesMustMatchItsHeader) {
  expect_file_error(write("empty.off", ""), "line 1: an OFF file starts with OFF");
  expect_file_error(write("short.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n"), "declares 3 vertices and 1 faces");
  expect_file_error(write("index.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 7\n"), "line 6: face 0");
  expect_file_error(write("corners.off", "OFF 3 1 0\n0 0 0\n1 0 0\n0 1 0\n2 0 1\n"), "corner count >= 3");
}
TEST_F(MeshFiles, PlyWithoutEndHeader) {
  expect_file_error(write("open.ply", "ply\nformat ascii 1.0\n"), "no end_header");
}

TEST_F(MeshFiles, ValidationErrorsNameTheFile) {
  // An OFF whose third face is wound against the others.
  std::string text = off_text(box_);
  const rtcd::Mesh::Triangle t = box_.triangles()[2];
  const std::string face = "3 " + std::to_string(t[0]) + ' ' + std::to_string(t[1]) + ' ' + std::to_string(t[2]);
  const std::string flipped = "3 " + std::to_string(t[0]) + ' ' + std::to_string(t[2]) + ' ' + std::to_string(t[1]);
  text.replace(text.find(face), face.size(), flipped);
  try {
    rtcd::Mesh::load(write("flipped.off", text));
    ADD_FAILURE();
  } catch (const rtcd::MeshError& e) {
    EXPECT_EQ(e.kind(), rtcd::MeshErrorKind::inconsistent_winding);
    EXPECT_NE(std::string(e.what()).find("flipped.off"), std::string::npos);
  }
}

}  // namespace
