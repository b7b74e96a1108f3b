// Mesh validation and the data derived from it once: normals, adjacency,
// bounds, radius.
#include "rtcd/mesh.hpp"

#include <cmath>
#include <numbers>
#include <sstream>
#include <unordered_map>

#include <Eigen/Geometry>

#include "rtcd/error.hpp"

namespace rtcd {
namespace {

[[noreturn]] void fail(MeshErrorKind kind, std::optional<uint32_t> vertex, std::optional<uint32_t> triangle,
                       const std::string& what) {
  std::ostringstream s;
  s << "invalid mesh: " << what;
  throw MeshError(kind, vertex, triangle, s.str());
}

// Vertices of edge e in the numbering of Algorithm 2 (see mesh.hpp).
std::array<uint32_t, 2> edge_vertices(const Mesh::Triangle& t, int e) {
  switch (e) {
    case 0: return {t[2], t[0]};
    case 1: return {t[0], t[1]};
    default: return {t[1], t[2]};
  }
}

// Twice the area below which a triangle counts as zero-area, relative to its
// longest edge squared: below float resolution of its own vertices.
constexpr double kZeroAreaRelative = 1e-7;

}  // namespace

Mesh::Mesh(std::vector<Eigen::Vector3f> positions, std::vector<Triangle> triangles, MeshOptions options)
    : positions_(std::move(positions)), triangles_(std::move(triangles)) {
  validate_and_derive(options);
}

void Mesh::validate_and_derive(const MeshOptions& options) {
  const size_t nv = positions_.size(), nt = triangles_.size();
  if (nv == 0 || nt == 0)
    fail(MeshErrorKind::empty, {}, {},
         "mesh is empty (" + std::to_string(nv) + " vertices, " + std::to_string(nt) + " triangles)");
  if (nv > uint32_t(INT32_MAX) || nt > uint32_t(INT32_MAX))
    fail(MeshErrorKind::index_out_of_range, {}, {}, "mesh has more than 2^31 vertices or triangles");

  for (uint32_t v = 0; v < nv; ++v) {
    if (!positions_[v].allFinite()) {
      std::ostringstream s;
      s << "vertex " << v << " has a non-finite coordinate (" << positions_[v].x() << ", " << positions_[v].y()
        << ", " << positions_[v].z() << ")";
      fail(MeshErrorKind::non_finite_coordinate, v, {}, s.str());
    }
  }

  std::vector<uint8_t> used(nv, 0);
  for (uint32_t t = 0; t < nt; ++t) {
    const Triangle& tri = triangles_[t];
    for (uint32_t i : tri) {
      if (i >= nv)
        fail(MeshErrorKind::index_out_of_range, i, t,
             "triangle " + std::to_string(t) + " refers to vertex " + std::to_string(i) + " but the mesh has " +
                 std::to_string(nv) + " vertices");
      used[i] = 1;
    }
    if (tri[0] == tri[1] || tri[1] == tri[2] || tri[0] == tri[2]) {
      const uint32_t v = tri[0] == tri[1] || tri[0] == tri[2] ? tri[0] : tri[1];
      fail(MeshErrorKind::repeated_vertex, v, t,
           "triangle " + std::to_string(t) + " repeats vertex " + std::to_string(v));
    }
  }
  for (uint32_t v = 0; v < nv; ++v)
    if (!used[v]) fail(MeshErrorKind::unreferenced_vertex, v, {}, "vertex " + std::to_string(v) + " is used by no triangle");

  // Triangle normals and zero-area detection, in double.
  triangle_normals_.assign(nt, Eigen::Vector3f::Zero());
  zero_area_.assign(nt, 0);
  std::vector<Eigen::Vector3d> normals_d(nt, Eigen::Vector3d::Zero());
  double signed_volume6 = 0.0;
  for (uint32_t t = 0; t < nt; ++t) {
    const Eigen::Vector3d a = positions_[triangles_[t][0]].cast<double>();
    const Eigen::Vector3d b = positions_[triangles_[t][1]].cast<double>();
    const Eigen::Vector3d c = positions_[triangles_[t][2]].cast<double>();
    const Eigen::Vector3d n = (b - a).cross(c - a);
    const double longest2 = std::max({(b - a).squaredNorm(), (c - b).squaredNorm(), (a - c).squaredNorm()});
    signed_volume6 += a.dot(b.cross(c));
    if (n.norm() <= kZeroAreaRelative * longest2) {
      if (!options.allow_zero_area)
        fail(MeshErrorKind::zero_area_triangle, {}, t,
             "triangle " + std::to_string(t) +
                 " has zero area (set MeshOptions::allow_zero_area, or --allow-zero-area, to keep it)");
      zero_area_[t] = 1;
      ++report_.zero_area_triangles;
      continue;
    }
    normals_d[t] = n.normalized();
    triangle_normals_[t] = normals_d[t].cast<float>();
  }

  // Edge adjacency: each undirected edge may be used twice, once per direction.
  struct EdgeUse {
    uint32_t triangle;
    int edge;
    uint32_t from;
  };
  std::unordered_map<uint64_t, std::array<EdgeUse, 2>> edges;
  std::unordered_map<uint64_t, int> counts;
  edges.reserve(nt * 2);
  counts.reserve(nt * 2);
  neighbors_.assign(nt, {no_neighbor, no_neighbor, no_neighbor});
  for (uint32_t t = 0; t < nt; ++t) {
    for (int e = 0; e < 3; ++e) {
      const auto [from, to] = edge_vertices(triangles_[t], e);
      const uint64_t key = (uint64_t(std::min(from, to)) << 32) | std::max(from, to);
      int& count = counts[key];
      if (count == 2)
        fail(MeshErrorKind::non_manifold_edge, from, t,
             "edge (" + std::to_string(from) + ", " + std::to_string(to) + ") of triangle " + std::to_string(t) +
                 " is shared by more than two triangles");
      if (count == 1) {
        const EdgeUse& first = edges[key][0];
        if (first.from == from)
          fail(MeshErrorKind::inconsistent_winding, from, t,
               "triangle " + std::to_string(t) + " runs edge (" + std::to_string(from) + ", " +
                   std::to_string(to) + ") in the same direction as triangle " + std::to_string(first.triangle) +
                   ": winding is inconsistent");
        neighbors_[t][e] = int32_t(first.triangle);
        neighbors_[first.triangle][first.edge] = int32_t(t);
      }
      edges[key][count] = {t, e, from};
      ++count;
    }
  }
  for (const auto& [key, count] : counts)
    if (count == 1) ++report_.boundary_edges;
  if (!report_.open() && signed_volume6 < 0.0)
    fail(MeshErrorKind::inverted, {}, {}, "closed mesh has negative volume: its triangles face inward");

  // Angle-weighted vertex normals.
  std::vector<Eigen::Vector3d> vn(nv, Eigen::Vector3d::Zero());
  for (uint32_t t = 0; t < nt; ++t) {
    if (zero_area_[t]) continue;
    for (int k = 0; k < 3; ++k) {
      const Eigen::Vector3d p = positions_[triangles_[t][k]].cast<double>();
      const Eigen::Vector3d e1 = positions_[triangles_[t][(k + 1) % 3]].cast<double>() - p;
      const Eigen::Vector3d e2 = positions_[triangles_[t][(k + 2) % 3]].cast<double>() - p;
      const double angle = std::atan2(e1.cross(e2).norm(), e1.dot(e2));
      vn[triangles_[t][k]] += angle * normals_d[t];
    }
  }
  vertex_normals_.resize(nv);
  for (uint32_t v = 0; v < nv; ++v) {
    // A vertex touched only by zero-area triangles, or whose faces cancel,
    // has no direction to cast along: it casts no ray (zero normal).
    const double len = vn[v].norm();
    vertex_normals_[v] = len > 0 ? Eigen::Vector3f((vn[v] / len).cast<float>()) : Eigen::Vector3f::Zero();
  }

  for (const auto& p : positions_) {
    bounds_.extend(p.cast<double>());
    radius_ = std::max(radius_, p.cast<double>().norm());
  }
}

}  // namespace rtcd
