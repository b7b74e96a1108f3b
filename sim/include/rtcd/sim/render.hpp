// Snapshot renderer: rigid bodies ray traced with Embree, written as PNG.
// Meant for looking at a simulation state (bodies, ground, contact rays),
// not for speed: every call builds its scenes afresh.
#pragma once

#include <array>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "rtcd/geometry.hpp"
#include "rtcd/results.hpp"
#include "rtcd/shape.hpp"

namespace rtcd::sim {

// Triangles in the body's local frame; winding does not matter (shading is
// two-sided).
struct RenderMesh {
  std::vector<Eigen::Vector3f> positions;
  std::vector<std::array<uint32_t, 3>> triangles;
};

// What a body looks like in its own frame: its mesh, or its sphere or box
// tessellated. Throws UsageError for a half-space, which has no finite look
// (see ground_square).
RenderMesh look_of(const Shape& shape);

// The ground drawn as a square of half side `half` around `centre`, in the
// plane z = 0 of the ground's frame.
RenderMesh ground_square(const Eigen::Vector3d& centre, double half);

// The colours every view of a scene gives its bodies: kind `kind` (cycling
// through six), static bodies and the ground.
Eigen::Vector3f kind_colour(size_t kind);
inline const Eigen::Vector3f kStaticColour{0.6f, 0.6f, 0.65f};
inline const Eigen::Vector3f kGroundColour{0.82f, 0.82f, 0.78f};

// One placed copy of meshes[mesh].
struct RenderInstance {
  uint32_t mesh = 0;
  Pose pose;
  Eigen::Vector3f color{0.7f, 0.7f, 0.7f};  // RGB in [0, 1]
};

// A segment in world frame drawn over the shaded image, e.g. a contact ray.
struct RenderLine {
  Eigen::Vector3d from, to;
  Eigen::Vector3f color{1, 0, 0};
};

// Contacts as red lines: each the segment a solver sees, from the contact
// point along the normal by the projected depth; or, with `full_rays`, the
// whole ray, along its direction by its depth (a grazing ray is long).
std::vector<RenderLine> contact_lines(std::span<const Contact> contacts, bool full_rays = false);

// Perspective pinhole camera; fov_degrees is the vertical field of view.
struct Camera {
  Eigen::Vector3d eye, target, up = Eigen::Vector3d::UnitZ();
  double fov_degrees = 40;
};

struct Image {
  int width = 0, height = 0;
  std::vector<uint8_t> rgb;  // width * height * 3 bytes, row-major, top row first
};

// A camera looking at `box` from the front-right (-y, +x), above (z is up),
// far enough that all of the box is in view for images at least as wide as
// they are tall. An empty box gives a view of the unit box around the origin.
Camera frame_camera(const Aabb& box);

// Ray traces the instances (one Embree scene per mesh, instanced with each
// pose): Lambert plus ambient shading from a fixed light with a shadow ray,
// on a light gradient background. Lines are drawn on top with a depth test
// against the surfaces: visible parts solid, hidden parts dimmed. The same
// input always gives the same bytes. Throws UsageError for an instance or
// triangle index out of range, a degenerate camera, a size outside
// [1, 16384], or when Embree reports an error (with Embree's message).
Image render(std::span<const RenderMesh> meshes, std::span<const RenderInstance> instances,
             std::span<const RenderLine> lines, const Camera& camera, int width, int height);

// Throws UsageError naming the path when it cannot be written, or when the
// image's size and its pixel buffer disagree.
void write_png(const std::string& path, const Image& image);

}  // namespace rtcd::sim
