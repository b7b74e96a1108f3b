// Snapshot renderer: coverage, determinism, line depth test, PNG output.
#include <array>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "rtcd/error.hpp"
#include "rtcd/mesh_gen.hpp"
#include "rtcd/sim/render.hpp"

namespace {

using rtcd::sim::Camera;
using rtcd::sim::Image;
using rtcd::sim::RenderInstance;
using rtcd::sim::RenderLine;
using rtcd::sim::RenderMesh;

using Rgb = std::array<uint8_t, 3>;

RenderMesh cube(double half_side) {
  const rtcd::Mesh mesh = rtcd::gen::box(Eigen::Vector3d::Constant(half_side));
  RenderMesh out;
  out.positions.assign(mesh.positions().begin(), mesh.positions().end());
  out.triangles.assign(mesh.triangles().begin(), mesh.triangles().end());
  return out;
}

RenderInstance placed(const Eigen::Vector3d& position, const Eigen::Vector3f& color = {0.7f, 0.7f, 0.7f}) {
  RenderInstance instance;
  instance.pose.position = position;
  instance.color = color;
  return instance;
}

Rgb pixel(const Image& image, int x, int y) {
  const size_t i = 3 * (size_t(y) * image.width + x);
  return {image.rgb[i], image.rgb[i + 1], image.rgb[i + 2]};
}

// Looking along +y at the origin from 6 units away, z up: the origin is the
// image centre and +z runs straight up the image.
Camera front_camera() {
  Camera camera;
  camera.eye = {0, -6, 0};
  camera.target = {0, 0, 0};
  return camera;
}

constexpr int side = 200;

TEST(Render, CubeCoversTheCentreAndLeavesTheCornerBackground) {
  const std::vector<RenderMesh> meshes = {cube(0.5)};
  const std::vector<RenderInstance> instances = {placed({0, 0, 0})};
  Camera camera;
  camera.eye = {3, -4, 2};
  camera.target = {0, 0, 0};
  const Image image = rtcd::sim::render(meshes, instances, {}, camera, side, side);
  const Image empty = rtcd::sim::render(meshes, {}, {}, camera, side, side);
  ASSERT_EQ(image.width, side);
  ASSERT_EQ(image.height, side);
  ASSERT_EQ(image.rgb.size(), size_t(side) * side * 3);

  const Rgb centre = pixel(image, side / 2, side / 2);
  EXPECT_NE(centre, pixel(empty, side / 2, side / 2));
  // A grey body stays grey; the background is tinted blue.
  EXPECT_NEAR(int(centre[0]), int(centre[2]), 2);
  EXPECT_EQ(pixel(image, 2, 2), pixel(empty, 2, 2));
  EXPECT_EQ(pixel(image, side - 3, side - 3), pixel(empty, side - 3, side - 3));
}

TEST(Render, EmptySceneIsAVerticalGradient) {
  const Image image = rtcd::sim::render({}, {}, {}, front_camera(), 64, 48);
  for (int y = 0; y < 48; ++y) EXPECT_EQ(pixel(image, 0, y), pixel(image, 63, y));
  EXPECT_NE(pixel(image, 0, 0), pixel(image, 0, 47));
}

TEST(Render, SameInputGivesTheSameBytes) {
  const std::vector<RenderMesh> meshes = {cube(0.5), cube(0.25)};
  std::vector<RenderInstance> instances = {placed({0, 0, 0}, {0.8f, 0.3f, 0.2f}), placed({1.2, 0.3, 0.1}),
                                           placed({-0.9, 0.5, 0.4}, {0.2f, 0.5f, 0.9f})};
  instances[1].mesh = 1;
  instances[2].pose.orientation = Eigen::Quaterniond(Eigen::AngleAxisd(0.6, Eigen::Vector3d(1, 2, 3).normalized()));
  const std::vector<RenderLine> lines = {{{-1, -1, -1}, {1, 1, 1}, {0, 1, 0}}, {{0, -2, 0.5}, {0, 2, 0.5}}};
  const Camera camera = rtcd::sim::frame_camera(rtcd::Aabb{{-1.5, -1, -1}, {1.5, 1, 1}});
  const Image first = rtcd::sim::render(meshes, instances, lines, camera, 160, 120);
  const Image second = rtcd::sim::render(meshes, instances, lines, camera, 160, 120);
  EXPECT_EQ(first.rgb, second.rgb);
}

TEST(Render, FrameCameraSeesTheWholeBox) {
  const std::vector<RenderMesh> meshes = {cube(0.5)};
  const std::vector<RenderInstance> instances = {placed({10, 20, 5})};
  const Camera camera = rtcd::sim::frame_camera(rtcd::Aabb{{9.5, 19.5, 4.5}, {10.5, 20.5, 5.5}});
  const int width = 160, height = 120;
  const Image image = rtcd::sim::render(meshes, instances, {}, camera, width, height);
  const Image empty = rtcd::sim::render(meshes, {}, {}, camera, width, height);
  EXPECT_NE(pixel(image, width / 2, height / 2), pixel(empty, width / 2, height / 2));
  for (int x = 0; x < width; ++x) {
    EXPECT_EQ(pixel(image, x, 0), pixel(empty, x, 0));
    EXPECT_EQ(pixel(image, x, height - 1), pixel(empty, x, height - 1));
  }
  for (int y = 0; y < height; ++y) {
    EXPECT_EQ(pixel(image, 0, y), pixel(empty, 0, y));
    EXPECT_EQ(pixel(image, width - 1, y), pixel(empty, width - 1, y));
  }
}

TEST(Render, VisibleLineFromTheTargetIsDrawnSolid) {
  // The cube sits behind the target, so the whole line is in front of it.
  const std::vector<RenderMesh> meshes = {cube(0.5)};
  const std::vector<RenderInstance> instances = {placed({0, 3, 0})};
  const std::vector<RenderLine> lines = {{{0, 0, 0}, {0, 0, 1}, {1, 0, 0}}};
  const Image with_line = rtcd::sim::render(meshes, instances, lines, front_camera(), side, side);
  const Image without = rtcd::sim::render(meshes, instances, {}, front_camera(), side, side);
  // z = 1 at distance 6 projects 1 / 6 / tan(20 deg) of the half height above the centre: row 54.
  for (int y = 60; y < 98; ++y)
    for (const int x : {side / 2 - 1, side / 2}) {
      EXPECT_EQ(pixel(with_line, x, y), (Rgb{255, 0, 0})) << x << ", " << y;
      EXPECT_NE(pixel(without, x, y), (Rgb{255, 0, 0}));
    }
  // Away from the line nothing changes.
  EXPECT_EQ(pixel(with_line, side / 2 + 10, 80), pixel(without, side / 2 + 10, 80));
  EXPECT_EQ(pixel(with_line, side / 2, 40), pixel(without, side / 2, 40));
}

TEST(Render, HiddenPartOfALineIsDimmed) {
  // The line stands 2 units behind the cube: its lower part (rows 76 to 99)
  // is behind the cube, its top (rows 66 to 74) over the background.
  const std::vector<RenderMesh> meshes = {cube(0.5)};
  const std::vector<RenderInstance> instances = {placed({0, 0, 0})};
  const std::vector<RenderLine> lines = {{{0, 2, 0}, {0, 2, 1}, {1, 0, 0}}};
  const Image with_line = rtcd::sim::render(meshes, instances, lines, front_camera(), side, side);
  const Image without = rtcd::sim::render(meshes, instances, {}, front_camera(), side, side);
  const int x = side / 2;
  for (int y = 68; y < 74; ++y) EXPECT_EQ(pixel(with_line, x, y), (Rgb{255, 0, 0})) << y;
  for (int y = 80; y < 98; ++y) {
    const Rgb dimmed = pixel(with_line, x, y), plain = pixel(without, x, y);
    EXPECT_NE(dimmed, (Rgb{255, 0, 0})) << y;
    EXPECT_GT(int(dimmed[0]), int(plain[0])) << y;
    EXPECT_LT(int(dimmed[1]), int(plain[1])) << y;
  }
}

TEST(Render, BadInputThrowsUsageError) {
  const std::vector<RenderMesh> meshes = {cube(0.5)};
  std::vector<RenderInstance> instances = {placed({0, 0, 0})};
  instances[0].mesh = 1;
  EXPECT_THROW(rtcd::sim::render(meshes, instances, {}, front_camera(), 8, 8), rtcd::UsageError);
  EXPECT_THROW(rtcd::sim::render(meshes, {}, {}, front_camera(), 0, 8), rtcd::UsageError);
  Camera degenerate = front_camera();
  degenerate.target = degenerate.eye;
  EXPECT_THROW(rtcd::sim::render(meshes, {}, {}, degenerate, 8, 8), rtcd::UsageError);
  std::vector<RenderMesh> broken = {cube(0.5)};
  broken[0].triangles[3][1] = 99;
  EXPECT_THROW(rtcd::sim::render(broken, {}, {}, front_camera(), 8, 8), rtcd::UsageError);
}

std::string temp_path(const std::string& name) {
  return (std::filesystem::path(::testing::TempDir()) / name).string();
}

uint32_t big_endian(const std::vector<unsigned char>& bytes, size_t at) {
  return uint32_t(bytes[at]) << 24 | uint32_t(bytes[at + 1]) << 16 | uint32_t(bytes[at + 2]) << 8 | bytes[at + 3];
}

TEST(Render, WritePngWritesSignatureAndSize) {
  const Image image = rtcd::sim::render({}, {}, {}, front_camera(), 37, 23);
  const std::string path = temp_path("rtcd_render_test_size.png");
  rtcd::sim::write_png(path, image);
  std::ifstream file(path, std::ios::binary);
  const std::vector<unsigned char> bytes{std::istreambuf_iterator<char>(file), std::istreambuf_iterator<char>()};
  std::filesystem::remove(path);
  ASSERT_GE(bytes.size(), 24u);
  const std::vector<unsigned char> signature = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
  EXPECT_TRUE(std::equal(signature.begin(), signature.end(), bytes.begin()));
  EXPECT_EQ(std::string(bytes.begin() + 12, bytes.begin() + 16), "IHDR");
  EXPECT_EQ(big_endian(bytes, 16), 37u);
  EXPECT_EQ(big_endian(bytes, 20), 23u);
}

TEST(Render, WritePngToAMissingDirectoryThrowsNamingThePath) {
  const Image image = rtcd::sim::render({}, {}, {}, front_camera(), 4, 4);
  const std::string path = temp_path("rtcd_render_test_no_such_directory/out.png");
  try {
    rtcd::sim::write_png(path, image);
    FAIL() << "no exception";
  } catch (const rtcd::UsageError& error) {
    EXPECT_NE(std::string(error.what()).find(path), std::string::npos) << error.what();
  }
}

}  // namespace
