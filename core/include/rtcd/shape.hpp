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

// Ray origins in the shape's local frame, each with its inward unit direction.
struct RaySources {
  std::vector<Eigen::Vector3f> origins;
  std::vector<Eigen::Vector3f> directions;
};

class Shape {
 public:
  using Geometry = std::variant<Mesh, Sphere, Box>;

  // A mesh casts from its vertices along the inward vertex normal.
  explicit Shape(Mesh mesh);
  // A sphere casts from the vertices of a level-2 icosphere (162 origins),
  // a box from its 8 corners along the corner diagonals; sampling_density > 0
  // adds that many origins per unit area, spread evenly over the surface.
  explicit Shape(Sphere sphere, double sampling_density = 0.0);
  explicit Shape(Box box, double sampling_density = 0.0);

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
