// What a body is made of: a mesh or a basic volume, with the ray origins it
// casts from when it is the source of a pair (section 1.3: vertices are a
// sampling of the surface, so any surface can cast rays).
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <span>
#include <type_traits>
#include <variant>
#include <vector>

#include <Eigen/Core>

#include "rtcd/export.hpp"
#include "rtcd/geometry.hpp"
#include "rtcd/mesh.hpp"

namespace rtcd {
RTCD_PUBLIC_BEGIN

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

// What a shape is the source of in a pair: ray origins in its local frame,
// each with its inward unit direction, and edges between them (a surface
// may cross another where no origin is inside it). Items number both:
// origins first, then edges from first_edge(). A tree of boxes over the
// items finds the few a pair's overlap holds without testing every one.
struct RaySources {
  std::vector<Eigen::Vector3f> origins;
  std::vector<Eigen::Vector3f> directions;
  // Each edge once, as two origin ids (the lower first), in that order.
  std::vector<std::array<uint32_t, 2>> edges;
  // A sphere: its radius, and one item after its origins (it has no
  // edges): its deepest point toward a sphere or box target, tested in
  // closed form (kernel/trace.h, rtcd_sphere_trace). 0 otherwise.
  float sphere_radius = 0.0f;

  uint32_t first_edge() const { return uint32_t(origins.size()); }
  uint32_t item_count() const { return uint32_t(origins.size() + edges.size() + (sphere_radius > 0.0f)); }
  // What the per-ray code places (kernel/tracer.h, rtcd_place_item): an
  // origin and its direction, or an edge's first end and the vector to its
  // other end.
  Eigen::Vector3f item_origin(uint32_t item) const {
    if (sphere_radius > 0.0f && item == first_edge()) return Eigen::Vector3f::Zero();
    return item < first_edge() ? origins[item] : origins[edges[item - first_edge()][0]];
  }
  Eigen::Vector3f item_direction(uint32_t item) const {
    if (item < first_edge()) return directions[item];
    if (sphere_radius > 0.0f) return Eigen::Vector3f::Zero();
    const auto& e = edges[item - first_edge()];
    return origins[e[1]] - origins[e[0]];
  }

  // A balanced binary tree over a permutation of the items: a node's are
  // order[begin, end); an inner node's children are nodes[child] and
  // nodes[child + 1]; child 0 marks a leaf (the root is node 0). The root
  // splits origins from the rest, so every other node holds items of one
  // kind.
  struct Node {
    Eigen::Vector3f lo, hi;
    uint32_t begin, end, child;
  };
  std::vector<Node> nodes;
  std::vector<uint32_t> order;

  // Builds the tree over the items; called once they are all in.
  void index();
  // Whether node n holds only mesh or box edges (no origin, no sphere item).
  bool edges_only(const Node& n) const {
    return sphere_radius == 0.0f && n.begin < n.end && order[n.begin] >= first_edge() &&
           order[n.end - 1] >= first_edge();
  }
  // Calls visit_leaf(n) for every leaf nodes[n] reached through nodes whose
  // box passes may_hold(lo, hi) (or may_hold(node)): a test that may pass a
  // box holding no wanted origin but never fails one holding one. Each leaf
  // at most once, in no particular order.
  template <class MayHold, class VisitLeaf>
  void visit_leaves(const MayHold& may_hold, const VisitLeaf& visit_leaf) const;
  // The items of node n.
  std::span<const uint32_t> items_of(uint32_t n) const {
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
    if constexpr (std::is_invocable_v<const MayHold&, const Node&>) {
      if (!may_hold(n)) continue;
    } else {
      if (!may_hold(n.lo, n.hi)) continue;
    }
    if (n.child != 0) {
      stack[top++] = n.child;
      stack[top++] = n.child + 1;
      continue;
    }
    visit_leaf(index);
  }
}

class DistanceBound;

class Shape {
 public:
  using Geometry = std::variant<Mesh, Sphere, Box, HalfSpace>;

  // A mesh casts from its vertices along the inward vertex normal; its edges
  // are the triangles' (a zero-length one included: it is never a candidate).
  explicit Shape(Mesh mesh);
  // A sphere casts from the vertices of a level-2 icosphere (162 origins)
  // and has no edges; a box casts from its 8 corners along the corner
  // diagonals, and its 12 edges join them; sampling_density > 0 adds that
  // many origins per unit area, spread evenly over the surface.
  explicit Shape(Sphere sphere, double sampling_density = 0.0);
  explicit Shape(Box box, double sampling_density = 0.0);
  // Bounds: |x|, |y| <= kMaxCoordinate, -kMaxCoordinate <= z <= 0.
  explicit Shape(HalfSpace half_space);

  const Geometry& geometry() const { return geometry_; }
  const Mesh* mesh() const { return std::get_if<Mesh>(&geometry_); }
  const RaySources& sources() const { return sources_; }
  const Aabb& bounds() const { return bounds_; }
  double radius() const { return radius_; }
  // Built on first use, once, and shared by every narrow phase and copy of
  // this shape (rtcd/distance_bound.hpp); safe to call from any thread.
  const DistanceBound& distance_bound() const;

 private:
  Geometry geometry_;
  RaySources sources_;
  Aabb bounds_;
  double radius_ = 0.0;
  struct LazyBound;
  std::shared_ptr<LazyBound> bound_;
};

RTCD_PUBLIC_END
}  // namespace rtcd
