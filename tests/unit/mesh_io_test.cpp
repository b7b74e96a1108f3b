// Loading OBJ, OFF, PLY and STL with the file's ids, and file errors.
#include <filesystem>
#include <fstream>

#include <algorithm>
#include <numeric>
#include <random>

#include <gtest/gtest.h>

#include "rtcd/backend.hpp"
#include "rtcd/error.hpp"
#include "rtcd/mesh_gen.hpp"
#include "rtcd/narrow_phase.hpp"

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

// A mesh as a file would list it: positions and faces in the file's order.
struct Listing {
  std::vector<Eigen::Vector3f> positions;
  std::vector<rtcd::Mesh::Triangle> faces;
};

// The blob with its vertex list and its face list shuffled.
Listing shuffled_blob() {
  const rtcd::Mesh blob = rtcd::gen::concave_blob(902, 3, 1.0);
  std::mt19937 rng(11);
  std::vector<uint32_t> new_id(blob.vertex_count()), face_order(blob.triangle_count());
  std::iota(new_id.begin(), new_id.end(), 0u);
  std::iota(face_order.begin(), face_order.end(), 0u);
  std::shuffle(new_id.begin(), new_id.end(), rng);
  std::shuffle(face_order.begin(), face_order.end(), rng);
  Listing l;
  l.positions.resize(blob.vertex_count());
  for (uint32_t v = 0; v < blob.vertex_count(); ++v) l.positions[new_id[v]] = blob.positions()[v];
  for (uint32_t f : face_order) {
    const auto& t = blob.triangles()[f];
    l.faces.push_back({new_id[t[0]], new_id[t[1]], new_id[t[2]]});
  }
  return l;
}

std::string as_off(const Listing& l) {
  std::ostringstream s;
  s.precision(9);
  s << "OFF\n" << l.positions.size() << ' ' << l.faces.size() << " 0\n";
  for (const auto& p : l.positions) s << p.x() << ' ' << p.y() << ' ' << p.z() << '\n';
  for (const auto& t : l.faces) s << "3 " << t[0] << ' ' << t[1] << ' ' << t[2] << '\n';
  return s.str();
}
std::string as_obj(const Listing& l) {
  std::ostringstream s;
  s.precision(9);
  for (const auto& p : l.positions) s << "v " << p.x() << ' ' << p.y() << ' ' << p.z() << '\n';
  for (const auto& t : l.faces) s << "f " << t[0] + 1 << ' ' << t[1] + 1 << ' ' << t[2] + 1 << '\n';
  return s.str();
}
std::string as_ply(const Listing& l) {
  std::ostringstream s;
  s.precision(9);
  s << "ply\nformat ascii 1.0\nelement vertex " << l.positions.size()
    << "\nproperty float x\nproperty float y\nproperty float z\nelement face " << l.faces.size()
    << "\nproperty list uchar int vertex_indices\nend_header\n";
  for (const auto& p : l.positions) s << p.x() << ' ' << p.y() << ' ' << p.z() << '\n';
  for (const auto& t : l.faces) s << "3 " << t[0] << ' ' << t[1] << ' ' << t[2] << '\n';
  return s.str();
}

// Every id a step reports is the file's: a contact's vertex is the file's
// vertex at its origin, its triangle (when the file's body is the target)
// the file's face whose normal it reports.
TEST_F(MeshFiles, ContactIdsAreTheFilesOnShuffledFiles) {
  const Listing l = shuffled_blob();
  for (const auto& [name, text] : {std::pair{"blob.off", as_off(l)}, std::pair{"blob.obj", as_obj(l)},
                                   std::pair{"blob.ply", as_ply(l)}}) {
    SCOPED_TRACE(name);
    const rtcd::Mesh m = rtcd::Mesh::load(write(name, text));
    ASSERT_EQ(m.vertex_count(), l.positions.size());
    ASSERT_EQ(m.triangle_count(), l.faces.size());
    for (size_t v = 0; v < l.positions.size(); ++v) ASSERT_EQ(m.positions()[v], l.positions[v]) << v;
    for (size_t f = 0; f < l.faces.size(); ++f) ASSERT_EQ(m.triangles()[f], l.faces[f]) << f;

    auto narrow = rtcd::make_narrow_phase("basic");
    const auto file_shape = narrow->add_shape(std::make_shared<rtcd::Shape>(m));
    const auto other = narrow->add_shape(std::make_shared<rtcd::Shape>(rtcd::gen::concave_blob(902, 4, 0.8)));
    const rtcd::BodyId a = narrow->add_body(file_shape, {});
    rtcd::Pose pose_b;
    pose_b.position = {1.1, 0.2, 0.1};
    const rtcd::BodyId b = narrow->add_body(other, pose_b);
    const rtcd::BodyPair pair{a, b};
    const rtcd::StepResult r = narrow->detect(std::span(&pair, 1));
    size_t from_file = 0, into_file = 0;
    for (const auto& c : r.contacts) {
      if (c.source_body == a) {
        ++from_file;
        EXPECT_EQ(c.origin.cast<float>(), l.positions[c.vertex]);
      } else {
        ++into_file;
        const auto& t = l.faces[size_t(c.triangle)];
        const Eigen::Vector3d n = (l.positions[t[1]] - l.positions[t[0]])
                                      .cross(l.positions[t[2]] - l.positions[t[0]])
                                      .cast<double>()
                                      .normalized();
        EXPECT_NEAR(c.normal.dot(n), 1.0, 1e-5);
      }
    }
    EXPECT_GT(from_file, 5u);
    EXPECT_GT(into_file, 5u);
  }
}

TEST_F(MeshFiles, PolygonsAreFannedFromTheirFirstCorner) {
  // A cube of six quads: face k becomes triangles 2k and 2k + 1.
  const std::string text =
      "OFF\n8 6 0\n0 0 0\n1 0 0\n0 1 0\n1 1 0\n0 0 1\n1 0 1\n0 1 1\n1 1 1\n"
      "4 0 2 3 1\n4 4 5 7 6\n4 0 1 5 4\n4 2 6 7 3\n4 0 4 6 2\n4 1 3 7 5\n";
  const rtcd::Mesh m = rtcd::Mesh::load(write("quads.off", text));
  ASSERT_EQ(m.triangle_count(), 12u);
  EXPECT_EQ(m.triangles()[2], (rtcd::Mesh::Triangle{4, 5, 7}));
  EXPECT_EQ(m.triangles()[3], (rtcd::Mesh::Triangle{4, 7, 6}));
  EXPECT_FALSE(m.report().open());
}

TEST_F(MeshFiles, CoincidentVerticesStayDistinctUnlessWelded) {
  // Two tetrahedra touching at the origin, each with a vertex of its own
  // there: two rays along opposite normals. Welded, the fans' normals cancel.
  const fs::path pinch = fs::path(RTCD_DATA_DIR) / "defects" / "pinch_split.off";
  const rtcd::Mesh m = rtcd::Mesh::load(pinch);
  ASSERT_EQ(m.vertex_count(), 8u);
  EXPECT_EQ(m.positions()[0], m.positions()[4]);
  EXPECT_NEAR(m.vertex_normals()[0].dot(-Eigen::Vector3f::Ones().normalized()), 1.0f, 1e-6f);
  EXPECT_NEAR(m.vertex_normals()[4].dot(Eigen::Vector3f::Ones().normalized()), 1.0f, 1e-6f);
  rtcd::MeshOptions weld;
  weld.weld = true;
  const rtcd::Mesh welded = rtcd::Mesh::load(pinch, weld);
  EXPECT_EQ(welded.vertex_count(), 7u);
  EXPECT_LT(welded.vertex_normals()[0].norm(), 1e-6f);
}

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
TEST_F(MeshFiles, PlyHeaderIsCheckedLineByLine) {
  expect_file_error(write("open.ply", "ply\nformat ascii 1.0\n"), "no end_header");
  // Headers assimp would misread are refused before it sees them, by line.
  const std::string tail = "property float y\nproperty float z\nend_header\n";
  expect_file_error(write("type.ply", "ply\nformat ascii 1.0\nelement vertex 1\nproperty fl;oat x\n" + tail),
                    "line 4 (\"property fl;oat x\"): unknown property type");
  expect_file_error(write("twice.ply", "ply\nformat ascii 1.0\nelement vertex 1\nelement vertex 2\n" + tail),
                    "element \"vertex\" is declared twice");
  expect_file_error(write("word.ply", "ply\nformat ascii 1.0\nelement vertex 1\npropertii 1.0\n" + tail),
                    "unknown header keyword \"propertii\"");
  expect_file_error(write("format.ply", "ply\nformat binary 1.0\nelement vertex 1\nproperty float x\n" + tail),
                    "unknown format");
  // assimp ends this line at the vertical tab and then seeks forever (mesh_file fuzzer).
  expect_file_error(write("vt.ply", "ply\nformat binary_little_endian 1.0\nelement vertex 1\nproperty float x\n"
                                    "property float y\nproperty float z\nend_header\v\n"),
                    "end_header must stand alone on its line");
}

TEST_F(MeshFiles, PlyBinaryBodyIsCheckedAgainstItsHeader) {
  // assimp loops until its counts are read, however few bytes follow: a
  // body shorter than its header states is refused first (mesh_file fuzzer).
  auto ply = [](const std::string& faces, bool big) {
    std::string text = "ply\nformat binary_" + std::string(big ? "big" : "little") +
                       "_endian 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
                       "element face " + faces + "\nproperty list uchar int vertex_indices\nend_header\n";
    const float xyz[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
    auto put = [&](const void* p, size_t n) {
      std::string bytes(static_cast<const char*>(p), n);
      if (big) std::reverse(bytes.begin(), bytes.end());  // this machine is little-endian
      text += bytes;
    };
    for (const float& v : xyz) put(&v, 4);
    text += '\3';
    for (int32_t i = 0; i < 3; ++i) put(&i, 4);
    return text;
  };
  for (const bool big : {false, true}) {
    SCOPED_TRACE(big ? "big-endian" : "little-endian");
    const rtcd::MeshData data = rtcd::read_mesh_file(write("ok.ply", ply("1", big)));
    EXPECT_EQ(data.positions.size(), 3u);
    EXPECT_EQ(data.triangles.size(), 1u);
    expect_file_error(write("faces.ply", ply("999999999", big)), "PLY body ends at face 1 of 999999999");
    std::string cut = ply("1", big);
    cut.resize(cut.size() - 5);  // the list's count is there, its values are not
    expect_file_error(write("cut.ply", cut), "PLY body ends at face 0 of 1");
    std::string huge = ply("1", big);
    huge[huge.size() - 13] = '\xff';  // a list of 255 indices in 12 bytes
    expect_file_error(write("count.ply", huge), "PLY body ends at face 0 of 1");
  }
}

TEST_F(MeshFiles, PlyAsciiBodyIsCheckedAgainstItsHeader) {
  // assimp allocates whatever a list's count says: a count the line does
  // not hold is refused first, naming the line (mesh_file fuzzer).
  const std::string header =
      "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
      "element face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n";
  EXPECT_NO_THROW(rtcd::read_mesh_file(write("ok.ply", header + "3 0 1 2\n")));
  expect_file_error(write("count.ply", header + "300000000 0 1 2\n"),
                    "PLY body line 13 (\"300000000 0 1 2\"): list count");
  expect_file_error(write("nul.ply", header + std::string("3\0 0 1 2\n", 9)), "list count");
  expect_file_error(write("extra.ply", header + "3 0 1 2 7\n"), "more values than the header's face properties");
  expect_file_error(write("short.ply", header.substr(0, header.size() - 6)), "PLY body ends at vertex 2 of 3");
  // A value that is not a number makes assimp throw and leak the mesh it was
  // building (fuzz/regressions/mesh_file/ply_leak_malformed_body): refused first.
  const std::string vertices = header.substr(0, header.find("0 0 0\n"));
  expect_file_error(write("word.ply", vertices + "0 0 0\n1 ;0 0\n0 1 0\n3 0 1 2\n"),
                    "PLY body line 11 (\"1 ;0 0\"): \";0\" is not a number");
  expect_file_error(write("index.ply", header + "3 0 x 2\n"), "\"x\" is not a number");
  EXPECT_NO_THROW(rtcd::read_mesh_file(write("forms.ply", vertices + "+1 -.5 1e-3\n.5 0. -0\n0 1 0\n3 0 1 2\n")));
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
