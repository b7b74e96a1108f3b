// What a body is made of: a mesh or a basic volume, with the ray origins it
// casts from when it is the source of a pair (section 1.3: vertices are a
// sampling of the surface, so any surface can cast rays).
#pragma once

#include <memory>
#include <variant>
#include <vector>

#include <Eigen/Core>

#include "rtcd/geometry.hpp"
#include "rtcd/mesh.hpp"

namespace rtcd {

struct Sphere {
  double radius = 1.0;
};

struct Box {
  Eigen::Vector3d half_extents = Eigen::Vector3d::Ones();
};

// The half-space z <= 0 of its local frame: a ground whose only exit is its
// plane z = 0 (outward normal +z), so a ray from a body sunk into it leaves
// upward by the depth below the plane, never through a far side face as it
// would from a box. It casts no rays; its face id is 0. For the motion bound
// of equation 2.1 it has no extent (radius 0): only the other body's radius
// counts.
struct HalfSpace {};

// Ray origins in the shape's local frame, each with its inward unit direction.
struct RaySources {
  std::vector<Eigen::Vector3f> origins;
  std::vector<Eigen::Vector3f> directions;
};

class Shape {
 public:
  using Geometry = std::variant<Mesh, Sphere, Box, HalfSpace>;

  // A mesh casts from its vertices along the inward vertex normal.
  explicit Shape(Mesh mesh);
  // A sphere casts from the vertices of a level-2 icosphere (162 origins),
  // a box from its 8 corners along the corner diagonals; sampling_density > 0
  // adds that many origins per unit area, spread evenly over the surface.
  explicit Shape(Sphere sphere, double sampling_density = 0.0);
  explicit Shape(Box box, double sampling_density = 0.0);
  // Bounds: |x|, |y| <= kMaxCoordinate, -kMaxCoordinate <= z <= 0.
  explicit Shape(HalfSpace half_space);

  const Geometry& geometry() const { return geometry_; }
  const Mesh* mesh() const { return std::get_if<Mesh>(&geometry_); }
  const RaySources& sources() const { return sources_; }
  const Aabb& bounds() const { return bounds_; }
  double radius() const { return radius_; }

 private:
  Geometry geometry_;
  RaySources sources_;
  Aabb bounds_;
  double radius_ = 0.0;
};

}  // namespace rtcd
