// What a body is made of: a mesh or a basic volume, with the ray origins it
// casts from when it is the source of a pair (section 1.3: vertices are a
// sampling of the surface, so any surface can cast rays).
#pragma once

#include <cstdint>
#include <memory>
#include <span>
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

// Ray origins in the shape's local frame, each with its inward unit
// direction, and a tree of boxes over them: a pair's overlap holds a few of
// a body's origins, found without testing every one.
struct RaySources {
  std::vector<Eigen::Vector3f> origins;
  std::vector<Eigen::Vector3f> directions;

  // A balanced binary tree over a permutation of the origins: a node's are
  // order[begin, end); an inner node's children are nodes[child] and
  // nodes[child + 1]; child 0 marks a leaf (the root is node 0).
  struct Node {
    Eigen::Vector3f lo, hi;
    uint32_t begin, end, child;
  };
  std::vector<Node> nodes;
  std::vector<uint32_t> order;

  // Builds the tree over the origins; called once they are all in.
  void index();
  // Calls visit_leaf(n) for every leaf nodes[n] reached through nodes whose
  // box passes may_hold(lo, hi): a test that may pass a box holding no
  // wanted origin but never fails one holding one. Each leaf at most once,
  // in no particular order.
  template <class MayHold, class VisitLeaf>
  void visit_leaves(const MayHold& may_hold, const VisitLeaf& visit_leaf) const;
  // The origins of node n.
  std::span<const uint32_t> origins_of(uint32_t n) const {
    return {order.data() + nodes[n].begin, nodes[n].end - nodes[n].begin};
  }
};

template <class MayHold, class VisitLeaf>
void RaySources::visit_leaves(const MayHold& may_hold, const VisitLeaf& visit_leaf) const {
  if (nodes.empty()) return;
  uint32_t stack[64];  // depth <= log2(origins) + 1 for median splits
  int top = 0;
  stack[top++] = 0;
  while (top > 0) {
    const uint32_t index = stack[--top];
    const Node& n = nodes[index];
    if (!may_hold(n.lo, n.hi)) continue;
    if (n.child != 0) {
      stack[top++] = n.child;
      stack[top++] = n.child + 1;
      continue;
    }
    visit_leaf(index);
  }
}

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
