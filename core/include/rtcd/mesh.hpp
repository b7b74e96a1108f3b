// A validated triangle mesh with everything the narrow phase derives from
// it once: unit normals, edge adjacency, bounds and radius.
#pragma once

#include <array>
#include <cstdint>
#include <filesystem>
#include <span>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "rtcd/export.hpp"
#include "rtcd/geometry.hpp"

namespace rtcd {
RTCD_PUBLIC_BEGIN

struct MeshOptions {
  // Keep zero-area triangles (common in scanned meshes) instead of rejecting
  // the mesh. They stay in the triangle list, are never hit, and are counted
  // in MeshReport::zero_area_triangles.
  bool allow_zero_area = false;
  // Join vertices at bit-identical positions (a triangle soup's corners)
  // into one, numbered in the order of their first occurrence. Off by
  // default: coincident vertices stay distinct, each with its own fan,
  // normal and ray, and ids stay the caller's (the file's).
  bool weld = false;
};

// The coordinates a mesh may use in its own frame. Beyond the largest, the
// single-precision ray/triangle test overflows (its distance numerator grows
// with the cube of the coordinates); below the smallest body size its
// products underflow. docs/ARCHITECTURE.md ("Sizes") derives both.
inline constexpr double kMaxCoordinate = 1e12;
inline constexpr double kMinBodySize = 1e-9;  // bounding-box diagonal
// Largest ratio of two bodies' bounding radii for which a penetration of
// 1% of the smaller body is still resolved in the larger body's frame.
inline constexpr double kMaxSizeRatio = 1e4;

// What validation found that is allowed but worth knowing.
struct MeshReport {
  uint32_t boundary_edges = 0;         // edges used by one triangle: the mesh is open
  uint32_t zero_area_triangles = 0;    // kept because MeshOptions::allow_zero_area
  uint32_t unreferenced_vertices = 0;  // used by no triangle: no normal, no ray
  bool open() const { return boundary_edges > 0; }
};

// Triangle winding is counter-clockwise seen from outside: the normal
// (v1 - v0) x (v2 - v0) points out of the body. Edge e of a triangle is
// numbered as in Algorithm 2: 0 = (v2, v0), 1 = (v0, v1), 2 = (v1, v2);
// neighbors()[t][e] is the triangle across it, or no_neighbor.
class Mesh {
 public:
  using Triangle = std::array<uint32_t, 3>;
  using Neighbors = std::array<int32_t, 3>;
  static constexpr int32_t no_neighbor = -1;

  // Validates and derives; throws MeshError naming the first offending
  // vertex or triangle. Nothing is repaired silently.
  Mesh(std::vector<Eigen::Vector3f> positions, std::vector<Triangle> triangles, MeshOptions options = {});

  // Loads OBJ, OFF, PLY or STL (read_mesh_file) and validates. Vertex and
  // triangle ids are the file's. Throws MeshError naming the path.
  static Mesh load(const std::filesystem::path& path, MeshOptions options = {});

  std::span<const Eigen::Vector3f> positions() const { return positions_; }
  std::span<const Triangle> triangles() const { return triangles_; }
  std::span<const Eigen::Vector3f> vertex_normals() const { return vertex_normals_; }      // angle-weighted, unit
  std::span<const Eigen::Vector3f> triangle_normals() const { return triangle_normals_; }  // unit; zero when zero-area
  std::span<const Neighbors> neighbors() const { return neighbors_; }
  std::span<const uint8_t> zero_area() const { return zero_area_; }  // 1 for a kept zero-area triangle
  const Aabb& bounds() const { return bounds_; }
  // Largest distance of a vertex from the body origin (maxRadius of eq. 2.1).
  double radius() const { return radius_; }
  const MeshReport& report() const { return report_; }
  // Closed, and every vertex on or behind every triangle's plane (to 1e-6 of
  // the radius): a line enters it once and leaves it once. Judged only for
  // meshes of at most kMaxConvexTest vertex-triangle products (false above).
  bool convex() const { return convex_; }
  static constexpr double kMaxConvexTest = 1e8;

  // Per triangle f, what the fold check of kernel/trace.h needs to certify,
  // without casting a ray, that a segment from a point of f into its inner
  // side crosses no other face: the ring (the triangles sharing a vertex
  // with f that reach into its inner side) to test by their planes, and the
  // clearance (no other face reaching into f's inner side comes closer to
  // f; a few triangle sizes at most, the reach of the search). A ring
  // face is tested by its plane as stored here, so the test reads no vertex.
  struct FoldGuard {
    struct Face {
      float clearance;
      float offset;  // n . v0, along the float unit normal of triangle_normals()
      float size;    // |v0|_1, which sizes the ring test's tolerance
    };
    std::vector<Face> faces;
    std::vector<uint32_t> ring_first;  // f's ring: ring[ring_first[f] .. ring_first[f + 1])
    std::vector<int32_t> ring;
  };
  const FoldGuard& fold_guard() const { return fold_guard_; }

  size_t vertex_count() const { return positions_.size(); }
  size_t triangle_count() const { return triangles_.size(); }

 private:
  void validate_and_derive(const MeshOptions& options);

  std::vector<Eigen::Vector3f> positions_;
  std::vector<Triangle> triangles_;
  std::vector<Eigen::Vector3f> vertex_normals_;
  std::vector<Eigen::Vector3f> triangle_normals_;
  std::vector<Neighbors> neighbors_;
  std::vector<uint8_t> zero_area_;
  Aabb bounds_;
  double radius_ = 0.0;
  MeshReport report_;
  bool convex_ = false;
  FoldGuard fold_guard_;
};

// A mesh file as its author wrote it, before validation. Vertices are the
// file's vertex list in its order; a face of n corners becomes n - 2
// consecutive triangles fanned from its first corner, (c0, ck, ck+1) for
// k = 1 .. n-2, in the file's face order, so a file of triangles keeps its
// face ids. STL stores no shared vertices: its corners are welded by exact
// position, numbered in order of first occurrence. OBJ is read with
// tinyobjloader, PLY and STL with assimp, OFF by rtcd itself (assimp 5.2
// crashes on malformed OFF and renumbers vertices). Throws MeshError (kind
// file) naming the path and, where there is one, the line.
struct MeshData {
  std::vector<Eigen::Vector3f> positions;
  std::vector<Mesh::Triangle> triangles;
};
MeshData read_mesh_file(const std::filesystem::path& path);

// Maps every vertex to the first vertex at the bit-identical position (0 and
// -0 are one position): the identity when no two vertices coincide.
std::vector<uint32_t> coincident_representatives(std::span<const Eigen::Vector3f> positions);

// Joins coincident vertices into their first occurrence; the survivors keep
// their order and triangles are renumbered (MeshOptions::weld, STL files).
void weld_coincident(std::vector<Eigen::Vector3f>& positions, std::vector<Mesh::Triangle>& triangles);

// Writes a Wavefront OBJ that Mesh::load reads back to the same mesh.
void save_obj(const Mesh& mesh, const std::filesystem::path& path);

RTCD_PUBLIC_END
}  // namespace rtcd
