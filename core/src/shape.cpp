// Shapes and their ray sources.
#include "rtcd/shape.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <mutex>
#include <numbers>
#include <sstream>

#include "rtcd/distance_bound.hpp"
#include "rtcd/error.hpp"
#include "rtcd/mesh_gen.hpp"

namespace rtcd {
namespace {

void check_density(double density) {
  if (!std::isfinite(density) || density < 0 || density > 1e7)
    throw UsageError("sampling density " + std::to_string(density) + " is outside [0, 1e7] origins per unit area");
}

// Volumes obey the meshes' size range (mesh.hpp): the same single-precision
// tests run on them.
void check_size(double extent, double diagonal, const std::string& what) {
  if (extent > kMaxCoordinate || diagonal < kMinBodySize) {
    std::ostringstream s;
    s << what << " is outside the supported sizes (coordinates up to " << kMaxCoordinate << ", a diagonal of at least "
      << kMinBodySize << ")";
    throw UsageError(s.str());
  }
}

void add_source(RaySources& s, const Eigen::Vector3d& origin, const Eigen::Vector3d& inward) {
  s.origins.push_back(origin.cast<float>());
  s.directions.push_back(inward.normalized().cast<float>());
}

// Origins per leaf: a leaf's origins are tested one by one.
constexpr uint32_t kSourcesPerLeaf = 16;
// Edges per leaf: fewer, so a distance bound turns away more of them by
// whole leaves (cpu_executor.hpp, visit_near_leaves).
constexpr uint32_t kEdgesPerLeaf = 4;

}  // namespace

struct Shape::LazyBound {
  std::once_flag once;
  std::unique_ptr<DistanceBound> bound;
};

const DistanceBound& Shape::distance_bound() const {
  std::call_once(bound_->once, [&] { bound_->bound = std::make_unique<DistanceBound>(*this); });
  return *bound_->bound;
}

void RaySources::index() {
  nodes.clear();
  const uint32_t items = item_count();
  order.resize(items);
  std::iota(order.begin(), order.end(), 0u);
  if (items == 0) return;
  // Each item's box: an origin's point, an edge's two ends, a sphere's
  // bounds for its deepest point.
  std::vector<Eigen::Vector3f> lows(items), highs(items);
  for (uint32_t i = 0; i < items; ++i) {
    const Eigen::Vector3f a = item_origin(i), b = i < first_edge() ? a : Eigen::Vector3f(a + item_direction(i));
    lows[i] = a.cwiseMin(b);
    highs[i] = a.cwiseMax(b);
    if (i >= first_edge() && sphere_radius > 0.0f) {
      lows[i] = Eigen::Vector3f::Constant(-sphere_radius);
      highs[i] = Eigen::Vector3f::Constant(sphere_radius);
    }
  }
  nodes.push_back({Eigen::Vector3f::Zero(), Eigen::Vector3f::Zero(), 0, items, 0});
  // Each node's box, then a split at the median of the item boxes' centres
  // along its longest axis (ties by index, so the tree is the same on
  // every run).
  for (size_t i = 0; i < nodes.size(); ++i) {
    const uint32_t begin = nodes[i].begin, end = nodes[i].end;
    Eigen::Vector3f lo = lows[order[begin]], hi = highs[order[begin]];
    for (uint32_t k = begin; k < end; ++k) {
      lo = lo.cwiseMin(lows[order[k]]);
      hi = hi.cwiseMax(highs[order[k]]);
    }
    nodes[i].lo = lo;
    nodes[i].hi = hi;
    // The root: origins apart from edges (order is still the identity).
    const bool split_kinds = i == 0 && first_edge() > 0 && first_edge() < items;
    if (end - begin <= (begin >= first_edge() && i > 0 ? kEdgesPerLeaf : kSourcesPerLeaf) && !split_kinds) continue;
    nodes[i].child = uint32_t(nodes.size());
    if (split_kinds) {
      nodes.push_back({Eigen::Vector3f::Zero(), Eigen::Vector3f::Zero(), begin, first_edge(), 0});
      nodes.push_back({Eigen::Vector3f::Zero(), Eigen::Vector3f::Zero(), first_edge(), end, 0});
      continue;
    }
    int axis = 0;
    (hi - lo).maxCoeff(&axis);
    const uint32_t mid = begin + (end - begin) / 2;
    auto centre = [&](uint32_t item) { return lows[item][axis] + highs[item][axis]; };
    std::nth_element(order.begin() + begin, order.begin() + mid, order.begin() + end, [&](uint32_t a, uint32_t b) {
      return centre(a) < centre(b) || (centre(a) == centre(b) && a < b);
    });
    nodes.push_back({Eigen::Vector3f::Zero(), Eigen::Vector3f::Zero(), begin, mid, 0});
    nodes.push_back({Eigen::Vector3f::Zero(), Eigen::Vector3f::Zero(), mid, end, 0});
  }
}

Shape::Shape(Mesh mesh) : geometry_(std::move(mesh)), bound_(std::make_shared<LazyBound>()) {
  const Mesh& m = std::get<Mesh>(geometry_);
  sources_.origins.assign(m.positions().begin(), m.positions().end());
  sources_.directions.reserve(m.vertex_count());
  for (const auto& n : m.vertex_normals()) sources_.directions.push_back(-n);
  // Each edge once: the triangles' edges, ordered and deduplicated.
  for (const auto& t : m.triangles())
    for (int k = 0; k < 3; ++k)
      sources_.edges.push_back({std::min(t[k], t[(k + 1) % 3]), std::max(t[k], t[(k + 1) % 3])});
  std::sort(sources_.edges.begin(), sources_.edges.end());
  sources_.edges.erase(std::unique(sources_.edges.begin(), sources_.edges.end()), sources_.edges.end());
  sources_.index();
  bounds_ = m.bounds();
  radius_ = m.radius();
}

Shape::Shape(Sphere sphere, double density) : geometry_(sphere), bound_(std::make_shared<LazyBound>()) {
  if (!std::isfinite(sphere.radius) || sphere.radius <= 0)
    throw UsageError("sphere radius " + std::to_string(sphere.radius) + " must be finite and > 0");
  check_size(sphere.radius, 2 * sphere.radius, "sphere radius");
  check_density(density);
  const double r = sphere.radius;
  const Mesh ico = gen::icosphere(1.0, 2);
  for (const auto& p : ico.positions()) add_source(sources_, r * p.cast<double>(), -p.cast<double>());
  // Fibonacci lattice: evenly spread, deterministic.
  const long n = std::lround(density * 4 * std::numbers::pi * r * r);
  const double golden = std::numbers::pi * (3 - std::sqrt(5.0));
  for (long i = 0; i < n; ++i) {
    const double z = 1 - (2 * i + 1.0) / n, s = std::sqrt(1 - z * z), phi = golden * i;
    const Eigen::Vector3d u(s * std::cos(phi), s * std::sin(phi), z);
    add_source(sources_, r * u, -u);
  }
  sources_.sphere_radius = float(r);
  sources_.index();
  bounds_ = {Eigen::Vector3d::Constant(-r), Eigen::Vector3d::Constant(r)};
  radius_ = r;
}

Shape::Shape(Box box, double density) : geometry_(box), bound_(std::make_shared<LazyBound>()) {
  const Eigen::Vector3d h = box.half_extents;
  if (!h.allFinite() || (h.array() <= 0).any()) throw UsageError("box half extents must be finite and > 0");
  check_size(h.maxCoeff(), 2 * h.norm(), "box half extents");
  check_density(density);
  for (int i = 0; i < 8; ++i) {
    const Eigen::Vector3d sign(i & 1 ? 1 : -1, i & 2 ? 1 : -1, i & 4 ? 1 : -1);
    add_source(sources_, sign.cwiseProduct(h), -sign);
  }
  // Corners i and i ^ bit differ along one axis: the 12 edges.
  for (uint32_t i = 0; i < 8; ++i)
    for (uint32_t bit : {1u, 2u, 4u})
      if ((i & bit) == 0) sources_.edges.push_back({i, i | bit});
  if (density > 0) {
    for (int axis = 0; axis < 3; ++axis) {
      const int u = (axis + 1) % 3, v = (axis + 2) % 3;
      const long nu = std::max(1L, std::lround(2 * h[u] * std::sqrt(density)));
      const long nv = std::max(1L, std::lround(2 * h[v] * std::sqrt(density)));
      for (double side : {1.0, -1.0})
        for (long i = 0; i < nu; ++i)
          for (long j = 0; j < nv; ++j) {
            Eigen::Vector3d p;
            p[axis] = side * h[axis];
            p[u] = h[u] * (2 * (i + 0.5) / nu - 1);
            p[v] = h[v] * (2 * (j + 0.5) / nv - 1);
            add_source(sources_, p, -side * Eigen::Vector3d::Unit(axis));
          }
    }
  }
  sources_.index();
  bounds_ = {-h, h};
  radius_ = h.norm();
}

Shape::Shape(HalfSpace half_space) : geometry_(half_space), bound_(std::make_shared<LazyBound>()) {
  bounds_ = {Eigen::Vector3d(-kMaxCoordinate, -kMaxCoordinate, -kMaxCoordinate),
             Eigen::Vector3d(kMaxCoordinate, kMaxCoordinate, 0.0)};
  radius_ = 0.0;
}

}  // namespace rtcd
