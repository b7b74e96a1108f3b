// Distance bounds: a grid of exact node distances for meshes, closed forms
// for volumes.
#include "rtcd/distance_bound.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "rtcd/near_search.hpp"
#include "rtcd/shape.hpp"

namespace rtcd {
namespace {

constexpr double kFar = 1e30;  // "no feature" in the distance transform: finite, so no inf - inf

// One line of Felzenszwalb and Huttenlocher's squared distance transform:
// d[q] = min over p of (q - p)^2 + f[p], exact on whole numbers.
void transform_line(const double* f, int n, double* d, int* v, double* z) {
  int k = 0;
  v[0] = 0;
  z[0] = -std::numeric_limits<double>::infinity();
  z[1] = std::numeric_limits<double>::infinity();
  for (int q = 1; q < n; ++q) {
    double s;
    while (true) {
      const int p = v[k];
      s = ((f[q] + double(q) * q) - (f[p] + double(p) * p)) / (2.0 * q - 2.0 * p);
      if (s > z[k]) break;
      --k;
    }
    ++k;
    v[k] = q;
    z[k] = s;
    z[k + 1] = std::numeric_limits<double>::infinity();
  }
  k = 0;
  for (int q = 0; q < n; ++q) {
    while (z[k + 1] < q) ++k;
    d[q] = double(q - v[k]) * (q - v[k]) + f[v[k]];
  }
}

// A double rounded down to the float at or below it.
float floor_float(double v) {
  float f = float(v);
  if (double(f) > v) f = std::nextafter(f, -std::numeric_limits<float>::infinity());
  return f;
}

}  // namespace

DistanceBound::DistanceBound(const Shape& shape) {
  bounds_ = shape.bounds();
  if (const auto* s = std::get_if<Sphere>(&shape.geometry())) {
    kind_ = Kind::sphere;
    radius_ = s->radius;
    return;
  }
  if (std::holds_alternative<Box>(shape.geometry())) {
    kind_ = Kind::box;
    return;
  }
  if (std::holds_alternative<HalfSpace>(shape.geometry())) {
    kind_ = Kind::half_space;
    return;
  }
  const Mesh& mesh = *shape.mesh();
  const Eigen::Vector3d size = bounds_.max - bounds_.min;
  const Aabb box = bounds_.grown(kPadding * 0.5 * size.norm());
  const Eigen::Vector3d extent = box.max - box.min;
  // The finest cell whose nodes fit the budget.
  const double budget = double(max_nodes(mesh.triangle_count()));
  double cell = std::cbrt(extent.prod() / budget);
  auto count = [&](double c) {
    std::array<int, 3> n;
    for (int a = 0; a < 3; ++a) n[a] = int(std::ceil(extent[a] / c)) + 1;
    return n;
  };
  while (double(count(cell)[0]) * count(cell)[1] * count(cell)[2] > budget) cell *= 1.01;
  cell_ = cell;
  nodes_ = count(cell);
  origin_ = box.min;
  const int nx = nodes_[0], ny = nodes_[1], nz = nodes_[2];
  const size_t total = size_t(nx) * ny * nz;
  auto index = [&](int x, int y, int z) { return (size_t(z) * ny + y) * nx + x; };
  auto node = [&](int x, int y, int z) { return Eigen::Vector3d(origin_ + cell * Eigen::Vector3d(x, y, z)); };

  // Exact distances within two cells of the surface: every node that near
  // lies in the grown box of its nearest triangle.
  const double band = 2.0 * cell;
  std::vector<double> exact(total, std::numeric_limits<double>::infinity());
  const auto& positions = mesh.positions();
  for (const auto& t : mesh.triangles()) {
    const Eigen::Vector3d a = positions[t[0]].cast<double>(), b = positions[t[1]].cast<double>(),
                          c = positions[t[2]].cast<double>();
    const Eigen::Vector3d lo = a.cwiseMin(b).cwiseMin(c).array() - band;
    const Eigen::Vector3d hi = a.cwiseMax(b).cwiseMax(c).array() + band;
    std::array<int, 3> from, to;
    for (int k = 0; k < 3; ++k) {
      from[k] = std::clamp(int(std::ceil((lo[k] - origin_[k]) / cell)), 0, nodes_[k] - 1);
      to[k] = std::clamp(int(std::floor((hi[k] - origin_[k]) / cell)), 0, nodes_[k] - 1);
    }
    for (int z = from[2]; z <= to[2]; ++z)
      for (int y = from[1]; y <= to[1]; ++y)
        for (int x = from[0]; x <= to[0]; ++x) {
          const Eigen::Vector3d p = node(x, y, z);
          double& e = exact[index(x, y, z)];
          e = std::min(e, (closest_on_triangle(p, a, b, c) - p).norm());
        }
  }

  // Farther out: every surface point has a node within half a cell's
  // diagonal r that lies within r of the surface, so a node's distance is
  // at least its distance to the nearest such node, less r.
  const double reach = 0.5 * std::sqrt(3.0) * cell;
  std::vector<double> squared(total);
  for (size_t i = 0; i < total; ++i) squared[i] = exact[i] <= reach ? 0.0 : kFar;
  const int longest = std::max({nx, ny, nz});
  std::vector<double> f(longest), d(longest), zs(longest + 1);
  std::vector<int> v(longest);
  auto pass = [&](int axis) {
    const int n = nodes_[axis], u = (axis + 1) % 3, w = (axis + 2) % 3;
    for (int j = 0; j < nodes_[w]; ++j)
      for (int i = 0; i < nodes_[u]; ++i) {
        std::array<int, 3> at{};
        at[u] = i;
        at[w] = j;
        for (int q = 0; q < n; ++q) {
          at[axis] = q;
          f[q] = squared[index(at[0], at[1], at[2])];
        }
        transform_line(f.data(), n, d.data(), v.data(), zs.data());
        for (int q = 0; q < n; ++q) {
          at[axis] = q;
          squared[index(at[0], at[1], at[2])] = std::min(d[q], kFar);
        }
      }
  };
  for (int axis = 0; axis < 3; ++axis) pass(axis);

  // Double rounding in the distances above, relative to the coordinates.
  const double slack = 1e-12 * (origin_.cwiseAbs().maxCoeff() + extent.maxCoeff());
  values_.resize(total);
  for (size_t i = 0; i < total; ++i) {
    const double far = std::max(band, std::sqrt(squared[i]) * cell - reach);
    values_[i] = floor_float(std::max((exact[i] <= band ? exact[i] : far) - slack, 0.0));
  }
}

rtcd_distance_grid DistanceBoundKernel::grid(const DistanceBound& b) {
  rtcd_distance_grid g{};
  using Kind = DistanceBound::Kind;
  g.kind = b.kind_ == Kind::sphere      ? RTCD_BOUND_SPHERE
           : b.kind_ == Kind::box       ? RTCD_BOUND_BOX
           : b.kind_ == Kind::half_space ? RTCD_BOUND_HALF_SPACE
                                        : RTCD_BOUND_GRID;
  for (int a = 0; a < 3; ++a) {
    g.lo[a] = b.bounds_.min[a];
    g.hi[a] = b.bounds_.max[a];
    g.origin[a] = b.origin_[a];
    g.nodes[a] = b.nodes_[a];
  }
  g.radius = b.radius_;
  g.cell = b.cell_;
  return g;
}

// The kernel's bound (kernel/near.h), which the devices' searches read too.
double DistanceBound::lower(const Eigen::Vector3d& p) const {
  const rtcd_distance_grid g = DistanceBoundKernel::grid(*this);
  return rtcd_distance_lower(&g, values_.data(), p.data());
}

}  // namespace rtcd
