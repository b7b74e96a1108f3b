// The mesh checker: topology from the file's ids, geometry in double, and
// self-intersections through a bounding-volume tree (Eigen's KdBVH).
#include "rtcd/mesh_check.hpp"

#include <algorithm>
#include <numeric>
#include <stdexcept>

#include <Eigen/Geometry>
#include <unsupported/Eigen/BVH>

#include "topology.hpp"

namespace rtcd {
namespace {

using Vec = Eigen::Vector3d;
using Tri = std::array<Vec, 3>;

struct UnionFind {
  std::vector<uint32_t> parent;
  explicit UnionFind(size_t n) : parent(n) { std::iota(parent.begin(), parent.end(), 0u); }
  uint32_t find(uint32_t x) {
    while (parent[x] != x) x = parent[x] = parent[parent[x]];
    return x;
  }
  void join(uint32_t a, uint32_t b) { parent[find(a)] = find(b); }
};

// Signed distances of a triangle's corners to a plane, snapped to 0 within
// `snap` (rounding of the double arithmetic, far below float resolution).
std::array<double, 3> distances(const Tri& t, const Vec& normal, const Vec& point, double snap) {
  std::array<double, 3> d;
  for (int i = 0; i < 3; ++i) {
    d[i] = normal.dot(t[i] - point);
    if (std::abs(d[i]) <= snap) d[i] = 0;
  }
  return d;
}

bool within(const std::array<double, 3>& d, double tol) {
  return std::abs(d[0]) <= tol && std::abs(d[1]) <= tol && std::abs(d[2]) <= tol;
}

bool one_side(const std::array<double, 3>& d) {
  return (d[0] > 0 && d[1] > 0 && d[2] > 0) || (d[0] < 0 && d[1] < 0 && d[2] < 0);
}

// The interval, along `axis`, where a triangle meets the plane its corner
// distances `d` are measured to (not all on one side).
std::array<double, 2> plane_interval(const Tri& t, const std::array<double, 3>& d, const Vec& axis) {
  double lo = INFINITY, hi = -INFINITY;
  auto take = [&](const Vec& p) {
    lo = std::min(lo, axis.dot(p));
    hi = std::max(hi, axis.dot(p));
  };
  for (int i = 0; i < 3; ++i) {
    const int j = (i + 1) % 3;
    if (d[i] == 0) take(t[i]);
    if (d[i] * d[j] < 0) take(t[i] + (t[j] - t[i]) * (d[i] / (d[i] - d[j])));
  }
  return {lo, hi};
}

// 2-D orientation of c against the segment a -> b, snapped to 0 within tol.
int orientation(const Eigen::Vector2d& a, const Eigen::Vector2d& b, const Eigen::Vector2d& c, double tol2) {
  const double o = (b - a).x() * (c - a).y() - (b - a).y() * (c - a).x();
  return o > tol2 ? 1 : (o < -tol2 ? -1 : 0);
}

// Coplanar triangles (projected to 2-D) overlap with positive area: an edge
// of one properly crosses an edge of the other, or a corner of one lies
// strictly inside the other, or both are the same triangle.
bool overlap_2d(const std::array<Eigen::Vector2d, 3>& p, const std::array<Eigen::Vector2d, 3>& q, double tol2) {
  auto strictly_inside = [&](const std::array<Eigen::Vector2d, 3>& t, const Eigen::Vector2d& x) {
    const int s = orientation(t[0], t[1], t[2], tol2);
    return s != 0 && orientation(t[0], t[1], x, tol2) == s && orientation(t[1], t[2], x, tol2) == s &&
           orientation(t[2], t[0], x, tol2) == s;
  };
  for (int i = 0; i < 3; ++i) {
    if (strictly_inside(p, q[i]) || strictly_inside(q, p[i])) return true;
    for (int j = 0; j < 3; ++j) {
      const auto &a = p[i], &b = p[(i + 1) % 3], &c = q[j], &d = q[(j + 1) % 3];
      const int o1 = orientation(a, b, c, tol2), o2 = orientation(a, b, d, tol2);
      const int o3 = orientation(c, d, a, tol2), o4 = orientation(c, d, b, tol2);
      if (o1 * o2 < 0 && o3 * o4 < 0) return true;
    }
  }
  // Same three corners: every test above is on a boundary.
  auto centroid = [](const std::array<Eigen::Vector2d, 3>& t) { return Eigen::Vector2d((t[0] + t[1] + t[2]) / 3); };
  return strictly_inside(p, centroid(q)) && strictly_inside(q, centroid(p));
}

std::array<Eigen::Vector2d, 3> project(const Tri& t, int drop) {
  const int x = (drop + 1) % 3, y = (drop + 2) % 3;
  return {Eigen::Vector2d(t[0][x], t[0][y]), Eigen::Vector2d(t[1][x], t[1][y]), Eigen::Vector2d(t[2][x], t[2][y])};
}

// Do p and q cross away from the `shared` corners they have in common
// (by position)? tol is a length: triangles within it of each other's plane
// are coplanar, and crossings shorter than it are touching.
bool triangles_cross(const Tri& p, const Tri& q, int shared, double tol) {
  const Vec np = (p[1] - p[0]).cross(p[2] - p[0]).normalized();
  const Vec nq = (q[1] - q[0]).cross(q[2] - q[0]).normalized();
  const double snap = 1e-6 * tol;
  const auto dp = distances(p, nq, q[0], snap), dq = distances(q, np, p[0], snap);
  if (one_side(dp) || one_side(dq)) return false;
  if (within(dp, tol) && within(dq, tol)) {
    int drop = 0;
    np.cwiseAbs().maxCoeff(&drop);
    return overlap_2d(project(p, drop), project(q, drop), tol * tol);
  }
  // Two planes through a shared edge meet only on that edge.
  if (shared >= 2) return false;
  const Vec axis = np.cross(nq).normalized();
  const auto a = plane_interval(p, dp, axis), b = plane_interval(q, dq, axis);
  return std::min(a[1], b[1]) - std::max(a[0], b[0]) > tol;
}

// A triangle and its box, as the tree stores it.
struct Boxed {
  uint32_t id;
  Eigen::AlignedBox3d box;
};
Eigen::AlignedBox3d bounding_box(const Boxed& b) { return b.box; }

// Collects the triangles whose boxes meet one query box.
struct BoxQuery {
  const Eigen::AlignedBox3d& box;
  std::vector<uint32_t>& hits;
  bool intersectVolume(const Eigen::AlignedBox3d& v) const { return v.intersects(box); }
  bool intersectObject(const Boxed& o) const {
    if (o.box.intersects(box)) hits.push_back(o.id);
    return false;
  }
};

bool usable(const Tri& t) {
  for (const Vec& v : t)
    if (!v.allFinite()) return false;
  return topology::shape_ratio(t[0], t[1], t[2]) > topology::kZeroAreaRatio;
}

MeshFinding make(std::string name, std::string element, bool defect, std::string meaning) {
  MeshFinding f;
  f.name = std::move(name);
  f.element = std::move(element);
  f.defect = defect;
  f.meaning = std::move(meaning);
  return f;
}

void add(MeshFinding& f, std::vector<uint32_t> example) {
  if (f.examples.size() < MeshCheck::kMaxExamples) f.examples.push_back(std::move(example));
  ++f.count;
}

}  // namespace

std::vector<std::array<uint32_t, 2>> self_intersections(std::span<const Eigen::Vector3f> positions,
                                                        std::span<const Mesh::Triangle> triangles, size_t limit) {
  const std::vector<uint32_t> same = coincident_representatives(positions);
  Eigen::AlignedBox3d all;
  std::vector<Tri> tris(triangles.size());
  std::vector<Boxed> boxed;
  for (uint32_t t = 0; t < triangles.size(); ++t) {
    if (std::any_of(triangles[t].begin(), triangles[t].end(), [&](uint32_t i) { return i >= positions.size(); }))
      continue;
    for (int k = 0; k < 3; ++k) tris[t][k] = positions[triangles[t][k]].cast<double>();
    if (!usable(tris[t])) continue;
    Eigen::AlignedBox3d box(tris[t][0]);
    box.extend(tris[t][1]).extend(tris[t][2]);
    all.extend(box);
    boxed.push_back({t, box});
  }
  std::vector<std::array<uint32_t, 2>> out;
  if (boxed.empty()) return out;
  // Touching closer than float resolution of the body is not crossing.
  const double tol = 1e-6 * all.diagonal().norm();
  for (Boxed& b : boxed)
    b.box = Eigen::AlignedBox3d((b.box.min().array() - tol).matrix(), (b.box.max().array() + tol).matrix());
  const Eigen::KdBVH<double, 3, Boxed> tree(boxed.begin(), boxed.end());
  std::vector<uint32_t> hits;
  for (const Boxed& b : boxed) {
    hits.clear();
    BoxQuery query{b.box, hits};
    Eigen::BVIntersect(tree, query);
    std::sort(hits.begin(), hits.end());
    for (uint32_t other : hits) {
      if (other <= b.id) continue;
      int shared = 0;
      for (uint32_t i : triangles[b.id])
        for (uint32_t j : triangles[other]) shared += same[i] == same[j];
      if (shared >= 3 || triangles_cross(tris[b.id], tris[other], shared, tol)) {
        out.push_back({b.id, other});
        if (out.size() >= limit) return out;
      }
    }
  }
  return out;
}

std::string self_intersection_warning(const Mesh& mesh, const std::string& name) {
  const auto pairs = self_intersections(mesh.positions(), mesh.triangles(), 4);
  if (pairs.empty()) return {};
  std::string s = name + ": the surface crosses itself (triangles ";
  for (size_t i = 0; i < pairs.size() && i < 3; ++i)
    s += (i ? ", " : "") + std::to_string(pairs[i][0]) + "x" + std::to_string(pairs[i][1]);
  s += pairs.size() > 3 ? ", ...)" : ")";
  return s + "; contacts near the crossing follow the ray rule, not the volume (rtcd check " + name + ")";
}

bool MeshCheck::fit() const {
  return std::none_of(findings.begin(), findings.end(), [](const MeshFinding& f) { return f.defect && f.count > 0; });
}

const MeshFinding& MeshCheck::finding(std::string_view name) const {
  for (const auto& f : findings)
    if (f.name == name) return f;
  throw std::out_of_range("no mesh finding named " + std::string(name));
}

MeshCheck check_mesh(std::span<const Eigen::Vector3f> positions, std::span<const Mesh::Triangle> triangles) {
  MeshCheck c;
  c.vertices = positions.size();
  c.triangles = triangles.size();
  MeshFinding range = make("out_of_range", "vertex", true,
                           "coordinates non-finite or beyond |x| <= 1e12, or a body smaller than 1e-9: single "
                           "precision cannot answer");
  MeshFinding bad_index = make("bad_indices", "triangle", true, "a triangle names a vertex that does not exist");
  MeshFinding repeated = make("repeated_vertex_triangles", "triangle", true,
                              "a triangle names one vertex twice: no surface");
  MeshFinding boundary = make("boundary_edges", "edge", true,
                              "edges used by one triangle: the mesh is open, inside and outside are undefined");
  MeshFinding non_manifold = make("non_manifold_edges", "edge", true,
                                  "edges shared by more than two triangles: a ray leaving there enters again");
  MeshFinding flipped = make("inconsistent_orientation", "triangle pair", true,
                             "neighbours that run their shared edge the same way: one faces inward, so rays "
                             "leaving through it read as entering");
  MeshFinding inverted = make("inverted", "mesh", true,
                              "closed, consistently oriented, negative volume: every triangle faces inward");
  MeshFinding crossing = make("self_intersections", "triangle pair", true,
                              "the surface crosses itself: near the crossing a vertex inside the volume can see a "
                              "front face first (the ray rule and the volume disagree)");
  MeshFinding zero_area = make("zero_area_triangles", "triangle", false,
                               "below float resolution: rejected unless --allow-zero-area, then never hit");
  MeshFinding slivers = make("sliver_triangles", "triangle", false,
                             "smallest altitude below 1/1000 of the longest edge: imprecise normal");
  MeshFinding pinch = make("pinch_vertices", "vertex", false,
                           "one vertex joining several fans: one ray along their averaged normal");
  MeshFinding coincident = make("coincident_vertices", "vertex group", false,
                                "distinct vertices at one position: each keeps its fan, normal and ray "
                                "(--weld joins them)");
  MeshFinding unreferenced = make("unreferenced_vertices", "vertex", false, "used by no triangle: cast no ray");

  const size_t nv = positions.size(), nt = triangles.size();
  for (uint32_t v = 0; v < nv; ++v) {
    if (!positions[v].allFinite() || positions[v].cwiseAbs().maxCoeff() > kMaxCoordinate) add(range, {v});
    else c.bounds.extend(positions[v].cast<double>());
  }
  if (!c.bounds.empty() && (c.bounds.max - c.bounds.min).norm() < kMinBodySize) add(range, {});

  // Triangles that reach only existing, distinct vertices go on to topology.
  std::vector<Mesh::Triangle> valid;
  std::vector<uint32_t> valid_id;
  std::vector<uint8_t> used(nv, 0);
  for (uint32_t t = 0; t < nt; ++t) {
    const auto& tri = triangles[t];
    if (std::any_of(tri.begin(), tri.end(), [&](uint32_t i) { return i >= nv; })) {
      add(bad_index, {t});
      continue;
    }
    for (uint32_t i : tri) used[i] = 1;
    if (tri[0] == tri[1] || tri[1] == tri[2] || tri[0] == tri[2]) {
      add(repeated, {t});
      continue;
    }
    valid.push_back(tri);
    valid_id.push_back(t);
    const Vec a = positions[tri[0]].cast<double>(), b = positions[tri[1]].cast<double>(),
              d = positions[tri[2]].cast<double>();
    if (!(a.allFinite() && b.allFinite() && d.allFinite())) continue;
    c.signed_volume += a.dot(b.cross(d)) / 6;
    const double ratio = topology::shape_ratio(a, b, d);
    if (ratio <= topology::kZeroAreaRatio) add(zero_area, {t});
    else if (ratio < 1e-3) add(slivers, {t});
  }
  for (uint32_t v = 0; v < nv; ++v)
    if (!used[v]) add(unreferenced, {v});

  // Edges, fans around each vertex (corner k of valid triangle i is 3i + k),
  // and components.
  UnionFind fans(valid.size() * 3), parts(nv);
  auto corner = [&](uint32_t i, uint32_t v) {
    const auto& tri = valid[i];
    return 3 * i + (tri[0] == v ? 0 : tri[1] == v ? 1 : 2);
  };
  topology::for_each_edge(topology::half_edges(valid), [&](std::span<const topology::HalfEdge> uses) {
    const topology::HalfEdge& e = uses[0];
    parts.join(e.from, e.to);
    if (uses.size() == 1) add(boundary, {std::min(e.from, e.to), std::max(e.from, e.to)});
    if (uses.size() > 2) add(non_manifold, {std::min(e.from, e.to), std::max(e.from, e.to)});
    if (uses.size() == 2) {
      if (uses[0].from == uses[1].from) add(flipped, {valid_id[uses[0].triangle], valid_id[uses[1].triangle]});
      for (uint32_t v : {e.from, e.to}) fans.join(corner(uses[0].triangle, v), corner(uses[1].triangle, v));
    }
  });
  std::vector<std::vector<uint32_t>> fan_roots(nv);
  for (uint32_t i = 0; i < valid.size(); ++i)
    for (uint32_t k = 0; k < 3; ++k) fan_roots[valid[i][k]].push_back(fans.find(3 * i + k));
  for (uint32_t v = 0; v < nv; ++v) {
    auto& roots = fan_roots[v];
    std::sort(roots.begin(), roots.end());
    if (std::unique(roots.begin(), roots.end()) - roots.begin() > 1) add(pinch, {v});
  }
  for (uint32_t v = 0; v < nv; ++v)
    if (used[v] && parts.find(v) == v) ++c.components;

  const std::vector<uint32_t> rep = coincident_representatives(positions);
  std::vector<std::vector<uint32_t>> groups(nv);
  for (uint32_t v = 0; v < nv; ++v) groups[rep[v]].push_back(v);
  for (auto& g : groups)
    if (g.size() > 1) add(coincident, std::move(g));

  c.closed = boundary.count == 0 && !valid.empty();
  if (c.closed && non_manifold.count == 0 && flipped.count == 0 && c.signed_volume < 0) add(inverted, {});
  for (const auto& pair : self_intersections(positions, triangles)) add(crossing, {pair[0], pair[1]});

  c.findings = {std::move(range),    std::move(bad_index), std::move(repeated),   std::move(boundary),
                std::move(non_manifold), std::move(flipped), std::move(inverted), std::move(crossing),
                std::move(zero_area), std::move(slivers), std::move(pinch), std::move(coincident),
                std::move(unreferenced)};
  return c;
}

}  // namespace rtcd
