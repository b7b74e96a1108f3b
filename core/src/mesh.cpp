// Mesh validation and the data derived from it once: normals, adjacency,
// bounds, radius.
#include "rtcd/mesh.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <numbers>
#include <sstream>
#include <unordered_map>

#include <Eigen/Geometry>

#include "rtcd/error.hpp"
#include "fold_clearance.hpp"
#include "topology.hpp"

namespace rtcd {
namespace {

[[noreturn]] void fail(MeshErrorKind kind, std::optional<uint32_t> vertex, std::optional<uint32_t> triangle,
                       const std::string& what) {
  std::ostringstream s;
  s << "invalid mesh: " << what;
  throw MeshError(kind, vertex, triangle, s.str());
}

}  // namespace

std::vector<uint32_t> coincident_representatives(std::span<const Eigen::Vector3f> positions) {
  struct Key {
    uint32_t bits[3];
    bool operator==(const Key& o) const { return std::memcmp(bits, o.bits, sizeof bits) == 0; }
  };
  struct Hash {
    size_t operator()(const Key& k) const {
      return (size_t(k.bits[0]) * 73856093u) ^ (size_t(k.bits[1]) * 19349663u) ^ (size_t(k.bits[2]) * 83492791u);
    }
  };
  std::unordered_map<Key, uint32_t, Hash> first;
  first.reserve(positions.size());
  std::vector<uint32_t> out(positions.size());
  for (uint32_t v = 0; v < positions.size(); ++v) {
    const float xyz[3] = {positions[v].x() + 0.0f, positions[v].y() + 0.0f, positions[v].z() + 0.0f};  // -0 -> 0
    Key key;
    std::memcpy(key.bits, xyz, sizeof xyz);
    out[v] = first.try_emplace(key, v).first->second;
  }
  return out;
}

void weld_coincident(std::vector<Eigen::Vector3f>& positions, std::vector<Mesh::Triangle>& triangles) {
  const std::vector<uint32_t> rep = coincident_representatives(positions);
  std::vector<uint32_t> new_id(positions.size());
  std::vector<Eigen::Vector3f> kept;
  for (uint32_t v = 0; v < positions.size(); ++v) {
    if (rep[v] == v) {
      new_id[v] = uint32_t(kept.size());
      kept.push_back(positions[v]);
    }
  }
  for (auto& t : triangles)
    for (uint32_t& i : t)
      if (i < positions.size()) i = new_id[rep[i]];  // an out-of-range index is left for validation to name
  positions = std::move(kept);
}

Mesh::Mesh(std::vector<Eigen::Vector3f> positions, std::vector<Triangle> triangles, MeshOptions options)
    : positions_(std::move(positions)), triangles_(std::move(triangles)) {
  if (options.weld) weld_coincident(positions_, triangles_);
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
    if (positions_[v].cwiseAbs().maxCoeff() > kMaxCoordinate) {
      std::ostringstream s;
      s << "vertex " << v << " at (" << positions_[v].x() << ", " << positions_[v].y() << ", " << positions_[v].z()
        << ") is beyond the supported coordinate range |x| <= " << kMaxCoordinate
        << " (single-precision ray tests overflow there); move the body's origin or rescale it";
      fail(MeshErrorKind::out_of_range, v, {}, s.str());
    }
  }

  for (const auto& p : positions_) {
    bounds_.extend(p.cast<double>());
    radius_ = std::max(radius_, p.cast<double>().norm());
  }
  if (const double size = (bounds_.max - bounds_.min).norm(); size < kMinBodySize) {
    std::ostringstream s;
    s << "the mesh spans " << size << ", below the smallest supported body size " << kMinBodySize
      << " (single-precision ray tests underflow); rescale it";
    fail(MeshErrorKind::out_of_range, {}, {}, s.str());
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
    if (!used[v]) ++report_.unreferenced_vertices;

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
    signed_volume6 += a.dot(b.cross(c));
    if (topology::shape_ratio(a, b, c) <= topology::kZeroAreaRatio) {
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

  // Edge adjacency: an edge is shared by at most two triangles, which run it
  // in opposite directions. Of several faults, the lowest triangle is named.
  neighbors_.assign(nt, {no_neighbor, no_neighbor, no_neighbor});
  std::optional<topology::HalfEdge> fault;
  bool fault_non_manifold = false;
  topology::for_each_edge(topology::half_edges(triangles_), [&](std::span<const topology::HalfEdge> uses) {
    const topology::HalfEdge* culprit = nullptr;
    if (uses.size() > 2) culprit = &uses[2];
    else if (uses.size() == 2 && uses[0].from == uses[1].from) culprit = &uses[1];
    if (culprit != nullptr && (!fault || culprit->triangle < fault->triangle)) {
      fault = *culprit;
      fault_non_manifold = uses.size() > 2;
    }
    if (uses.size() == 1) ++report_.boundary_edges;
    if (uses.size() == 2) {
      neighbors_[uses[0].triangle][uses[0].edge] = int32_t(uses[1].triangle);
      neighbors_[uses[1].triangle][uses[1].edge] = int32_t(uses[0].triangle);
    }
  });
  if (fault) {
    const std::string edge = "edge (" + std::to_string(fault->from) + ", " + std::to_string(fault->to) + ")";
    if (fault_non_manifold)
      fail(MeshErrorKind::non_manifold_edge, fault->from, fault->triangle,
           edge + " of triangle " + std::to_string(fault->triangle) + " is shared by more than two triangles");
    fail(MeshErrorKind::inconsistent_winding, fault->from, fault->triangle,
         "triangle " + std::to_string(fault->triangle) + " runs " + edge +
             " in the same direction as another triangle: winding is inconsistent");
  }
  if (!report_.open() && signed_volume6 < 0.0)
    fail(MeshErrorKind::inverted, {}, {}, "closed mesh has negative volume: its triangles face inward");

  // Convex: every vertex behind every face's plane (a concave mesh fails at
  // one of its first faces).
  if (!report_.open() && report_.zero_area_triangles == 0 && double(nv) * double(nt) <= kMaxConvexTest) {
    const double tolerance = 1e-6 * radius_;
    convex_ = true;
    for (uint32_t t = 0; t < nt && convex_; ++t) {
      const Eigen::Vector3d a = positions_[triangles_[t][0]].cast<double>();
      convex_ = std::all_of(positions_.begin(), positions_.end(), [&](const Eigen::Vector3f& p) {
        return normals_d[t].dot(p.cast<double>() - a) <= tolerance;
      });
    }
  }

  fold_guard_ = derive_fold_guard(positions_, triangles_, normals_d);

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
}

}  // namespace rtcd
