// A lower bound on how far a point lies from a shape's surface, read in
// O(1): what proves a pair of bodies apart without casting a ray
// (docs/ARCHITECTURE.md, Distance bounds). Unsigned: it says nothing
// of inside or outside, so open meshes get one too.
#pragma once

#include <array>
#include <cstddef>
#include <vector>

#include <Eigen/Core>

#include "rtcd/export.hpp"
#include "rtcd/geometry.hpp"

namespace rtcd {
RTCD_PUBLIC_BEGIN

class Shape;

class DistanceBound {
 public:
  // Meshes: a grid of nodes over the mesh's box grown by kPadding times half its
  // diagonal, at most max_nodes(triangles) of them; each node holds the exact distance
  // to the nearest triangle (computed in double within two cells of the
  // surface, beyond that a distance transform's lower bound), rounded down
  // to float. Volumes: closed form, no grid.
  explicit DistanceBound(const Shape& shape);

  // A lower bound on the distance from p (the shape's frame) to its
  // surface: max over the 8 nodes of p's cell of node value - |p - node|
  // (the distance is 1-Lipschitz), and never less than p's distance to the
  // mesh's box. At most the exact distance; on a mesh, at most about a cell's
  // diagonal below it near the surface.
  double lower(const Eigen::Vector3d& p) const;

  // The grid: nodes per axis (0 for volumes), cell size, bytes held.
  std::array<int, 3> nodes() const { return nodes_; }
  double cell() const { return cell_; }
  size_t bytes() const { return values_.size() * sizeof(float); }

  static constexpr double kPadding = 0.5;
  // Nodes a mesh's grid may take: kNodesPerTriangle a triangle, between
  // kMinNodes and kMaxNodes (a coarse box needs no megabyte).
  static constexpr size_t kMinNodes = size_t(1) << 12, kMaxNodes = size_t(1) << 18, kNodesPerTriangle = 300;
  static size_t max_nodes(size_t triangles) {
    return triangles * kNodesPerTriangle < kMinNodes   ? kMinNodes
           : triangles * kNodesPerTriangle > kMaxNodes ? kMaxNodes
                                                       : triangles * kNodesPerTriangle;
  }

 private:
  enum class Kind { grid, sphere, box, half_space } kind_ = Kind::grid;
  Aabb bounds_;               // meshes: the mesh's box; box: [-h, h]
  double radius_ = 0.0;       // sphere
  Eigen::Vector3d origin_ = Eigen::Vector3d::Zero();  // node (0, 0, 0)
  double cell_ = 0.0;
  std::array<int, 3> nodes_{0, 0, 0};
  std::vector<float> values_;  // x fastest

  // Reads the members for the kernel's search (kernel/near.h), which is this bound.
  friend struct DistanceBoundKernel;
};

RTCD_PUBLIC_END
}  // namespace rtcd
