// What the fold check of kernel/trace.h reads per triangle, derived once by
// Mesh: the faces near a triangle that a segment into its inner side could
// cross.
#pragma once

#include <span>

#include <Eigen/Core>

#include "rtcd/mesh.hpp"
#include "topology.hpp"

namespace rtcd {

// See Mesh::FoldGuard. The 1e-5 relative tolerance that decides "reaches
// into the inner side" lets folds thinner than the float rounding of the
// coordinates go unseen: coplanar neighbours of a flat region are ignored.
Mesh::FoldGuard derive_fold_guard(std::span<const Eigen::Vector3f> positions,
                                  std::span<const topology::Triangle> triangles,
                                  std::span<const Eigen::Vector3d> normals);

}  // namespace rtcd
