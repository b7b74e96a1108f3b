// Edges of a triangle list by vertex id, and the zero-area rule: what mesh
// validation and the mesh checker both read.
#pragma once

#include <algorithm>
#include <array>
#include <cstdint>
#include <span>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace rtcd::topology {

using Triangle = std::array<uint32_t, 3>;

// Twice the area over the longest edge squared (the smallest altitude over
// the longest edge): 0 for a degenerate triangle, sqrt(3)/2 when equilateral.
inline double shape_ratio(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c) {
  const double longest2 = std::max({(b - a).squaredNorm(), (c - b).squaredNorm(), (a - c).squaredNorm()});
  return longest2 > 0 ? (b - a).cross(c - a).norm() / longest2 : 0.0;
}
// At or below this ratio a triangle has zero area: below the float
// resolution of its own vertices.
inline constexpr double kZeroAreaRatio = 1e-7;

// Vertices of edge e in the numbering of Algorithm 2 (see mesh.hpp):
// 0 = (v2, v0), 1 = (v0, v1), 2 = (v1, v2).
inline std::array<uint32_t, 2> edge_vertices(const Triangle& t, int e) {
  switch (e) {
    case 0: return {t[2], t[0]};
    case 1: return {t[0], t[1]};
    default: return {t[1], t[2]};
  }
}

// One triangle's use of an undirected edge, running from `from` to `to`.
struct HalfEdge {
  uint64_t key;  // (min vertex << 32) | max vertex
  uint32_t triangle;
  uint32_t edge;
  uint32_t from, to;
};

// All half-edges sorted by undirected edge, then by triangle and edge: the
// uses of one edge are adjacent, in triangle order.
inline std::vector<HalfEdge> half_edges(std::span<const Triangle> triangles) {
  std::vector<HalfEdge> out;
  out.reserve(triangles.size() * 3);
  for (uint32_t t = 0; t < triangles.size(); ++t)
    for (uint32_t e = 0; e < 3; ++e) {
      const auto [from, to] = edge_vertices(triangles[t], int(e));
      out.push_back({(uint64_t(std::min(from, to)) << 32) | std::max(from, to), t, e, from, to});
    }
  std::sort(out.begin(), out.end(), [](const HalfEdge& a, const HalfEdge& b) {
    return a.key != b.key ? a.key < b.key : (a.triangle != b.triangle ? a.triangle < b.triangle : a.edge < b.edge);
  });
  return out;
}

// Calls f(span of the uses of one edge) for every undirected edge.
template <class F>
void for_each_edge(const std::vector<HalfEdge>& sorted, F&& f) {
  for (size_t i = 0; i < sorted.size();) {
    size_t j = i + 1;
    while (j < sorted.size() && sorted[j].key == sorted[i].key) ++j;
    f(std::span<const HalfEdge>(sorted.data() + i, j - i));
    i = j;
  }
}

}  // namespace rtcd::topology
