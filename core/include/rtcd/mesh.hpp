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

#include "rtcd/geometry.hpp"

namespace rtcd {

struct MeshOptions {
  // Keep zero-area triangles (common in scanned meshes) instead of rejecting
  // the mesh. They stay in the triangle list, are never hit, and are counted
  // in MeshReport::zero_area_triangles.
  bool allow_zero_area = false;
};

// What validation found that is allowed but worth knowing.
struct MeshReport {
  uint32_t boundary_edges = 0;       // edges used by one triangle: the mesh is open
  uint32_t zero_area_triangles = 0;  // kept because MeshOptions::allow_zero_area
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

  // Loads OBJ, OFF, PLY or STL through assimp. Corners at bit-identical
  // positions become one vertex (STL stores none shared); vertex ids follow
  // their first use by a face. Throws MeshError (kind file) naming the path.
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
};

// Writes a Wavefront OBJ that Mesh::load reads back to the same mesh.
void save_obj(const Mesh& mesh, const std::filesystem::path& path);

}  // namespace rtcd
