// The exact reference in double precision: a median-split bounding-volume
// tree over a mesh's triangles, Möller–Trumbore crossings, closest points on
// triangles; spheres and boxes in closed form.
#include "rtcd/oracle/exact.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>

#include <Eigen/Geometry>

#include "rtcd/geometry.hpp"

namespace rtcd::oracle {
namespace {

using Vec = Eigen::Vector3d;
using Box3 = Eigen::AlignedBox3d;
constexpr double kInf = std::numeric_limits<double>::infinity();

// Signed distance along the ray to the triangle's plane where the ray's line
// crosses the triangle, or NaN when it does not (or is parallel to it).
double line_crossing(const Vec& o, const Vec& d, const Vec& a, const Vec& b, const Vec& c) {
  const Vec e1 = b - a, e2 = c - a;
  const Vec p = d.cross(e2);
  const double det = e1.dot(p);
  if (det == 0.0) return std::nan("");
  const double inv = 1.0 / det;
  const Vec s = o - a;
  const double u = s.dot(p) * inv;
  if (u < 0.0 || u > 1.0) return std::nan("");
  const Vec q = s.cross(e1);
  const double v = d.dot(q) * inv;
  if (v < 0.0 || u + v > 1.0) return std::nan("");
  return e2.dot(q) * inv;
}

// Entry and exit of the ray's line through a box, as [t0, t1]; empty when t0 > t1.
void slab(const Box3& box, const Vec& o, const Vec& inv_d, double& t0, double& t1) {
  t0 = -kInf;
  t1 = kInf;
  for (int k = 0; k < 3; ++k) {
    double a = (box.min()[k] - o[k]) * inv_d[k], b = (box.max()[k] - o[k]) * inv_d[k];
    if (std::isnan(a) || std::isnan(b)) {  // origin on a slab plane of a parallel ray
      if (o[k] < box.min()[k] || o[k] > box.max()[k]) t0 = kInf;
      continue;
    }
    if (a > b) std::swap(a, b);
    t0 = std::max(t0, a);
    t1 = std::min(t1, b);
  }
}

// Three fixed directions in no special relation to any axis or to each other.
const Vec kDirections[3] = {Vec(1.0, 0.3713, 0.1287).normalized(), Vec(-0.2317, 1.0, 0.4419).normalized(),
                                  Vec(0.3329, -0.1863, 1.0).normalized()};

}  // namespace

struct ExactShape::Tree {
  struct Node {
    Box3 box;
    int32_t left = -1, right = -1;  // children; -1 in a leaf
    uint32_t first = 0, count = 0;  // range of `order` in a leaf
  };
  std::vector<Vec> positions;
  std::vector<std::array<uint32_t, 3>> triangles;
  std::vector<uint32_t> order;  // triangle ids, leaf by leaf
  std::vector<Node> nodes;
  bool closed = false;

  explicit Tree(const Mesh& mesh) : closed(!mesh.report().open()) {
    for (const auto& p : mesh.positions()) positions.push_back(p.cast<double>());
    triangles.assign(mesh.triangles().begin(), mesh.triangles().end());
    order.resize(triangles.size());
    std::iota(order.begin(), order.end(), 0u);
    std::vector<Vec> centroids;
    for (const auto& t : triangles) centroids.push_back((corner(t, 0) + corner(t, 1) + corner(t, 2)) / 3.0);
    build(0, uint32_t(order.size()), centroids);
  }

  const Vec& corner(const std::array<uint32_t, 3>& t, int k) const { return positions[t[k]]; }

  int32_t build(uint32_t first, uint32_t count, const std::vector<Vec>& centroids) {
    const int32_t id = int32_t(nodes.size());
    nodes.emplace_back();
    Box3 box, centre_box;
    for (uint32_t i = first; i < first + count; ++i) {
      for (int k = 0; k < 3; ++k) box.extend(corner(triangles[order[i]], k));
      centre_box.extend(centroids[order[i]]);
    }
    nodes[id].box = box;
    if (count <= 4) {
      nodes[id].first = first;
      nodes[id].count = count;
      return id;
    }
    int axis;
    centre_box.sizes().maxCoeff(&axis);
    const auto begin = order.begin() + first, mid = begin + count / 2, end = begin + count;
    std::nth_element(begin, mid, end, [&](uint32_t a, uint32_t b) { return centroids[a][axis] < centroids[b][axis]; });
    const int32_t left = build(first, count / 2, centroids);
    const int32_t right = build(first + count / 2, count - count / 2, centroids);
    nodes[id].left = left;
    nodes[id].right = right;
    return id;
  }

  // Nearest crossing of origin + t * direction with t >= 0: nearer boxes
  // first, boxes beyond the best crossing so far skipped. Ties go to the
  // lower triangle id.
  void nearest(const Vec& o, const Vec& d, double& t_best, int32_t& best) const {
    const Vec inv_d = d.cwiseInverse();
    t_best = kInf;
    best = -1;
    auto entry = [&](int32_t node) {
      double t0, t1;
      slab(nodes[node].box, o, inv_d, t0, t1);
      return t0 > t1 || t1 < 0.0 ? kInf : std::max(t0, 0.0);
    };
    std::pair<double, int32_t> stack[128];
    int top = 0;
    stack[top++] = {entry(0), 0};
    while (top > 0) {
      const auto [t_enter, id] = stack[--top];
      if (t_enter > t_best) continue;
      const Node& n = nodes[id];
      if (n.left < 0) {
        for (uint32_t i = n.first; i < n.first + n.count; ++i) {
          const auto& tri = triangles[order[i]];
          const double t = line_crossing(o, d, corner(tri, 0), corner(tri, 1), corner(tri, 2));
          if (t >= 0.0 && (t < t_best || (t == t_best && int32_t(order[i]) < best))) {
            t_best = t;
            best = int32_t(order[i]);
          }
        }
        continue;
      }
      const double tl = entry(n.left), tr = entry(n.right);
      // Nearer child last, so it is searched first.
      if (tl <= tr) {
        if (tr < kInf) stack[top++] = {tr, n.right};
        if (tl < kInf) stack[top++] = {tl, n.left};
      } else {
        if (tl < kInf) stack[top++] = {tl, n.left};
        if (tr < kInf) stack[top++] = {tr, n.right};
      }
    }
  }

  // Every crossing of o + t * d with 0 <= t <= 1: (t, +1 entering or -1
  // leaving), unordered.
  void crossings(const Vec& o, const Vec& d, std::vector<std::pair<double, int>>& out) const {
    const Vec inv_d = d.cwiseInverse();
    int32_t stack[128];
    int top = 0;
    stack[top++] = 0;
    while (top > 0) {
      const Node& n = nodes[stack[--top]];
      double t0, t1;
      slab(n.box, o, inv_d, t0, t1);
      if (t0 > t1 || t1 < 0.0 || t0 > 1.0) continue;
      if (n.left >= 0) {
        stack[top++] = n.left;
        stack[top++] = n.right;
        continue;
      }
      for (uint32_t i = n.first; i < n.first + n.count; ++i) {
        const auto& tri = triangles[order[i]];
        const double t = line_crossing(o, d, corner(tri, 0), corner(tri, 1), corner(tri, 2));
        if (!(t >= 0.0 && t <= 1.0)) continue;
        const double facing = (corner(tri, 1) - corner(tri, 0)).cross(corner(tri, 2) - corner(tri, 0)).dot(d);
        if (facing != 0.0) out.push_back({t, facing < 0.0 ? 1 : -1});
      }
    }
  }

  // Inside when the nearest crossing along d leaves the surface: for a
  // closed, consistently wound mesh the same verdict as the parity of all
  // crossings, found without visiting them all.
  bool leaves_first(const Vec& p, const Vec& d) const {
    double t;
    int32_t tri;
    nearest(p, d, t, tri);
    if (tri < 0) return false;
    const auto& v = triangles[tri];
    return (corner(v, 1) - corner(v, 0)).cross(corner(v, 2) - corner(v, 0)).dot(d) > 0.0;
  }

  // Squared distance to the nearest triangle, searching only closer than
  // `bound` (squared): a caller that needs only "nearer than r?" stops early.
  // `closest`, when given, receives the nearest point found.
  double squared_distance(const Vec& p, double bound, Vec* closest = nullptr) const {
    double best = bound;
    int32_t stack[128];
    int top = 0;
    stack[top++] = 0;
    while (top > 0) {
      const Node& n = nodes[stack[--top]];
      if (n.box.squaredExteriorDistance(p) >= best) continue;
      if (n.left < 0) {
        for (uint32_t i = n.first; i < n.first + n.count; ++i) {
          const auto& tri = triangles[order[i]];
          const Vec q = closest_on_triangle(p, corner(tri, 0), corner(tri, 1), corner(tri, 2));
          if (const double d2 = (q - p).squaredNorm(); d2 < best) {
            best = d2;
            if (closest) *closest = q;
          }
        }
        continue;
      }
      // Nearer child last, so it is searched first.
      const double dl = nodes[n.left].box.squaredExteriorDistance(p), dr = nodes[n.right].box.squaredExteriorDistance(p);
      stack[top++] = dl < dr ? n.right : n.left;
      stack[top++] = dl < dr ? n.left : n.right;
    }
    return best;
  }
};

ExactShape::ExactShape(std::shared_ptr<const Shape> shape) : shape_(std::move(shape)) {
  if (const Mesh* m = shape_->mesh()) tree_ = std::make_unique<Tree>(*m);
}
ExactShape::~ExactShape() = default;
ExactShape::ExactShape(ExactShape&&) noexcept = default;
ExactShape& ExactShape::operator=(ExactShape&&) noexcept = default;

bool ExactShape::closed() const { return !tree_ || tree_->closed; }

bool ExactShape::inside(const Vec& p) const {
  if (tree_) {
    const bool first = tree_->leaves_first(p, kDirections[0]);
    if (first == tree_->leaves_first(p, kDirections[1])) return first;
    return tree_->leaves_first(p, kDirections[2]);
  }
  if (const auto* s = std::get_if<Sphere>(&shape_->geometry())) return p.norm() < s->radius;
  if (std::holds_alternative<HalfSpace>(shape_->geometry())) return p.z() < 0.0;
  const Vec& h = std::get<Box>(shape_->geometry()).half_extents;
  return (p.cwiseAbs().array() < h.array()).all();
}

double ExactShape::distance(const Vec& p) const {
  if (tree_) return std::sqrt(tree_->squared_distance(p, kInf));
  if (const auto* s = std::get_if<Sphere>(&shape_->geometry())) return std::abs(p.norm() - s->radius);
  if (std::holds_alternative<HalfSpace>(shape_->geometry())) return std::abs(p.z());
  const Vec& h = std::get<Box>(shape_->geometry()).half_extents;
  const Vec q = p.cwiseAbs() - h;
  if ((q.array() <= 0).all()) return -q.maxCoeff();
  return q.cwiseMax(0.0).norm();
}

Vec ExactShape::closest_point(const Vec& p) const {
  if (tree_) {
    Vec q = p;
    tree_->squared_distance(p, kInf, &q);
    return q;
  }
  if (const auto* s = std::get_if<Sphere>(&shape_->geometry()))
    return p.isZero() ? Vec(0, 0, s->radius) : Vec(p.normalized() * s->radius);
  if (std::holds_alternative<HalfSpace>(shape_->geometry())) return {p.x(), p.y(), 0.0};
  const Vec& h = std::get<Box>(shape_->geometry()).half_extents;
  const Vec clamped = p.cwiseMax(-h).cwiseMin(h);
  if (clamped != p) return clamped;  // outside: the box's nearest point
  // Inside: onto the face with the least room.
  Eigen::Index axis = 0;
  (h - p.cwiseAbs()).minCoeff(&axis);
  Vec q = p;
  q[axis] = p[axis] < 0.0 ? -h[axis] : h[axis];
  return q;
}

bool ExactShape::within(const Vec& p, double radius) const {
  if (tree_) return tree_->squared_distance(p, radius * radius) < radius * radius;
  return distance(p) < radius;
}

bool ExactShape::first_hit(const Vec& o, const Vec& d, double& t_hit, int32_t& triangle) const {
  t_hit = kInf;
  triangle = -1;
  if (tree_) {
    tree_->nearest(o, d, t_hit, triangle);
  } else if (const auto* s = std::get_if<Sphere>(&shape_->geometry())) {
    const double b = o.dot(d), c = o.squaredNorm() - s->radius * s->radius, disc = b * b - c;
    if (disc >= 0.0) {
      const double near = -b - std::sqrt(disc), far = -b + std::sqrt(disc);
      const double t = near >= 0.0 ? near : far;
      if (t >= 0.0) {
        t_hit = t;
        triangle = 0;
      }
    }
  } else if (std::holds_alternative<HalfSpace>(shape_->geometry())) {
    // The plane z = 0 is the only surface.
    const double t = d.z() != 0.0 ? -o.z() / d.z() : -1.0;
    if (t >= 0.0) {
      t_hit = t;
      triangle = 0;
    }
  } else {
    const Vec& h = std::get<Box>(shape_->geometry()).half_extents;
    double t0, t1;
    slab(Box3(-h, h), o, d.cwiseInverse(), t0, t1);
    if (t0 <= t1 && t1 >= 0.0) {
      t_hit = t0 >= 0.0 ? t0 : t1;
      // The face: the axis whose plane the hit point lies on.
      const Vec hit = o + t_hit * d;
      int axis;
      (hit.cwiseAbs() - h).maxCoeff(&axis);
      triangle = 2 * axis + (hit[axis] > 0 ? 0 : 1);
    }
  }
  return triangle >= 0;
}

std::vector<ExactRay> ExactShape::rays_from(const Shape& source, const Pose& source_pose, const Pose& pose,
                                            double margin) const {
  const Pose to_local = pose.inverse() * source_pose;
  const Eigen::Matrix3d rotation = to_local.orientation.toRotationMatrix();
  const Aabb near_box = shape_->bounds().grown(margin);
  const RaySources& rs = source.sources();
  std::vector<ExactRay> out(rs.origins.size());
  for (size_t i = 0; i < rs.origins.size(); ++i) {
    const Vec p = rotation * rs.origins[i].cast<double>() + to_local.position;
    if (!near_box.contains(p)) continue;
    ExactRay& r = out[i];
    r.near = true;
    r.near_surface = within(p, margin);
    r.inside = closed() && inside(p);
    if (r.inside) {
      r.penetration = distance(p);
      const Vec d = (rotation * rs.directions[i].cast<double>()).normalized();
      double t;
      if (first_hit(p, d, t, r.triangle)) r.depth = t;
    }
  }
  return out;
}

double ExactShape::sphere_depth(const Shape& source, const Pose& source_pose, const Pose& pose) const {
  const auto* sphere = std::get_if<Sphere>(&source.geometry());
  if (sphere == nullptr) return -1.0;
  const Vec c = (pose.inverse() * source_pose).position;
  double depth = -1.0;
  if (const auto* s = std::get_if<Sphere>(&shape_->geometry())) {
    depth = sphere->radius + s->radius - c.norm();
  } else if (const auto* b = std::get_if<Box>(&shape_->geometry())) {
    const Vec q = c.cwiseMax(-b->half_extents).cwiseMin(b->half_extents);
    depth = q == c ? sphere->radius + distance(c) : sphere->radius - (c - q).norm();
  }
  return depth > 0.0 ? depth : -1.0;
}

std::vector<double> ExactShape::edge_depths(const Shape& source, const Pose& source_pose, const Pose& pose) const {
  const Pose to_local = pose.inverse() * source_pose;
  const Eigen::Matrix3d rotation = to_local.orientation.toRotationMatrix();
  const RaySources& rs = source.sources();
  const Aabb bounds = shape_->bounds();
  std::vector<double> out(rs.edges.size(), -1.0);
  if (!closed() || std::holds_alternative<HalfSpace>(shape_->geometry())) return out;
  std::vector<std::pair<double, int>> hits;
  for (size_t e = 0; e < rs.edges.size(); ++e) {
    const Vec p0 = rotation * rs.origins[rs.edges[e][0]].cast<double>() + to_local.position;
    const Vec p1 = rotation * rs.origins[rs.edges[e][1]].cast<double>() + to_local.position;
    const Vec d = p1 - p0;
    Aabb segment;
    segment.extend(p0);
    segment.extend(p1);
    if (d.isZero() || segment.intersection(bounds).empty() || inside(p0) || inside(p1)) continue;
    hits.clear();
    if (tree_) {
      tree_->crossings(p0, d, hits);
    } else {
      // Sphere or box: the line's span inside, in closed form.
      double t0 = kInf, t1 = -kInf;
      if (const auto* s = std::get_if<Sphere>(&shape_->geometry())) {
        const double a = d.squaredNorm(), b = p0.dot(d), c = p0.squaredNorm() - s->radius * s->radius;
        const double disc = b * b - a * c;
        if (disc > 0.0) {
          t0 = (-b - std::sqrt(disc)) / a;
          t1 = (-b + std::sqrt(disc)) / a;
        }
      } else {
        const Vec& h = std::get<Box>(shape_->geometry()).half_extents;
        slab(Box3(-h, h), p0, d.cwiseInverse(), t0, t1);
      }
      if (t0 < t1 && t0 > 0.0 && t1 < 1.0) hits = {{t0, 1}, {t1, -1}};
    }
    std::sort(hits.begin(), hits.end());
    double enter = -1.0;
    for (const auto& [t, sense] : hits) {
      if (sense > 0) {
        enter = t;
      } else if (enter >= 0.0) {
        if (t > enter) out[e] = std::max(out[e], distance(p0 + 0.5 * (enter + t) * d));
        enter = -1.0;
      }
    }
  }
  return out;
}

}  // namespace rtcd::oracle
