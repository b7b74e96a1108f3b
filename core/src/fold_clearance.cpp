// Per-triangle fold clearance: a uniform grid of triangle boxes, searched in
// growing shells around each triangle, with exact triangle distances in
// double for the triangles that reach into its inner side.
#include "fold_clearance.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>

#include <tbb/enumerable_thread_specific.h>

#include "parallel.hpp"
#include "rtcd/geometry.hpp"

namespace rtcd {
namespace {

using Vec = Eigen::Vector3d;

// Segment pq passes through triangle abc (not merely touching its plane
// from one side); coplanar cases are left to the distance terms.
bool segment_crosses(const Vec& p, const Vec& q, const Vec& a, const Vec& b, const Vec& c) {
  const Vec n = (b - a).cross(c - a);
  const double sp = n.dot(p - a), sq = n.dot(q - a);
  if ((sp > 0 && sq > 0) || (sp < 0 && sq < 0) || sp == sq) return false;
  const Vec x = p + (q - p) * (sp / (sp - sq));
  return n.dot((b - a).cross(x - a)) >= 0 && n.dot((c - b).cross(x - b)) >= 0 && n.dot((a - c).cross(x - c)) >= 0;
}

// Distance between two triangles: 0 if they meet, else the least of the
// vertex-triangle and edge-edge distances.
double triangle_distance(const std::array<Vec, 3>& f, const std::array<Vec, 3>& g) {
  for (int i = 0; i < 3; ++i)
    if (segment_crosses(f[i], f[(i + 1) % 3], g[0], g[1], g[2]) ||
        segment_crosses(g[i], g[(i + 1) % 3], f[0], f[1], f[2]))
      return 0.0;
  double best = std::numeric_limits<double>::infinity();
  for (int i = 0; i < 3; ++i) {
    best = std::min({best, (f[i] - closest_on_triangle(f[i], g[0], g[1], g[2])).norm(),
                     (g[i] - closest_on_triangle(g[i], f[0], f[1], f[2])).norm()});
    for (int j = 0; j < 3; ++j) best = std::min(best, segment_distance(f[i], f[(i + 1) % 3], g[j], g[(j + 1) % 3]));
  }
  return best;
}

// Shells of grid cells searched around a triangle's box: the clearance is
// capped at this many cell sizes, a few triangle sizes.
constexpr int kShells = 2;

}  // namespace

Mesh::FoldGuard derive_fold_guard(std::span<const Eigen::Vector3f> positions,
                                  std::span<const topology::Triangle> triangles,
                                  std::span<const Eigen::Vector3d> normals) {
  const size_t nt = triangles.size(), nv = positions.size();
  Mesh::FoldGuard guard;
  guard.faces.assign(nt, {0.0f, 0.0f, 0.0f});
  for (size_t t = 0; t < nt; ++t) {
    const Vec v0 = positions[triangles[t][0]].cast<double>();
    guard.faces[t].offset = float(normals[t].cast<float>().cast<double>().dot(v0));
    guard.faces[t].size = float(v0.cwiseAbs().sum());
  }
  guard.ring_first.assign(nt + 1, 0);
  auto corners = [&](size_t t) {
    return std::array<Vec, 3>{positions[triangles[t][0]].cast<double>(), positions[triangles[t][1]].cast<double>(),
                              positions[triangles[t][2]].cast<double>()};
  };

  // Each vertex's triangles (compressed rows).
  std::vector<uint32_t> fan_first(nv + 1, 0), fan(3 * nt);
  for (const auto& t : triangles)
    for (uint32_t v : t) ++fan_first[v + 1];
  for (size_t v = 1; v <= nv; ++v) fan_first[v] += fan_first[v - 1];
  {
    std::vector<uint32_t> fill(fan_first.begin(), fan_first.end() - 1);
    for (uint32_t t = 0; t < nt; ++t)
      for (uint32_t v : triangles[t]) fan[fill[v]++] = t;
  }

  // Cells about the mean face size, at most 8 per face. Zero-area
  // triangles are never hit: they are left out of the grid, and a mesh of
  // nothing else has nothing to guard.
  Vec lo = Vec::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
  double size_sum = 0;
  size_t faces = 0;
  for (size_t t = 0; t < nt; ++t) {
    if (normals[t].isZero()) continue;
    ++faces;
    const auto c = corners(t);
    const Vec tlo = c[0].cwiseMin(c[1]).cwiseMin(c[2]), thi = c[0].cwiseMax(c[1]).cwiseMax(c[2]);
    lo = lo.cwiseMin(tlo);
    hi = hi.cwiseMax(thi);
    size_sum += (thi - tlo).maxCoeff();
  }
  if (faces == 0) return guard;
  double h = size_sum / double(faces);  // > 0: a face with area spans some length
  // Counted in double: a few small triangles far apart would overflow integers.
  std::array<int64_t, 3> dims{};
  for (;;) {
    double cells = 1;
    for (int k = 0; k < 3; ++k) cells *= std::max(1.0, std::ceil((hi[k] - lo[k]) / h));
    const double most = double(8 * faces + 64);
    if (cells <= most) break;
    h *= std::max(1.25, std::cbrt(cells / most));
  }
  for (int k = 0; k < 3; ++k) dims[k] = std::max<int64_t>(1, int64_t(std::ceil((hi[k] - lo[k]) / h)));
  auto cell_of = [&](double x, int k) { return std::clamp<int64_t>(int64_t((x - lo[k]) / h), 0, dims[k] - 1); };
  auto box_cells = [&](const std::array<Vec, 3>& c, std::array<int64_t, 3>& a, std::array<int64_t, 3>& b) {
    for (int k = 0; k < 3; ++k) {
      a[k] = cell_of(std::min({c[0][k], c[1][k], c[2][k]}), k);
      b[k] = cell_of(std::max({c[0][k], c[1][k], c[2][k]}), k);
    }
  };
  auto index = [&](int64_t x, int64_t y, int64_t z) { return size_t((z * dims[1] + y) * dims[0] + x); };

  // Each triangle listed in every cell its box overlaps (compressed rows).
  std::vector<uint32_t> first(size_t(dims[0] * dims[1] * dims[2]) + 1, 0), members;
  for (int pass = 0; pass < 2; ++pass) {
    std::vector<uint32_t> fill;
    if (pass == 1) {
      for (size_t i = 1; i < first.size(); ++i) first[i] += first[i - 1];
      members.resize(first.back());
      fill.assign(first.begin(), first.end() - 1);
    }
    for (size_t t = 0; t < nt; ++t) {
      if (normals[t].isZero()) continue;
      std::array<int64_t, 3> a, b;
      box_cells(corners(t), a, b);
      for (int64_t z = a[2]; z <= b[2]; ++z)
        for (int64_t y = a[1]; y <= b[1]; ++y)
          for (int64_t x = a[0]; x <= b[0]; ++x) {
            if (pass == 0) ++first[index(x, y, z) + 1];
            else members[fill[index(x, y, z)]++] = uint32_t(t);
          }
    }
  }

  // Bounding spheres: most triangles near f are farther than the nearest
  // one found so far, which the sphere distance tells cheaply.
  std::vector<Vec> centre(nt);
  std::vector<double> bound(nt);
  for (size_t t = 0; t < nt; ++t) {
    const auto c = corners(t);
    centre[t] = (c[0] + c[1] + c[2]) / 3.0;
    bound[t] = std::sqrt(std::max({(c[0] - centre[t]).squaredNorm(), (c[1] - centre[t]).squaredNorm(),
                                   (c[2] - centre[t]).squaredNorm()}));
  }

  // Which triangles reach into f's inner side: below its plane by more
  // than the float rounding of the coordinates, off which a flat region's
  // coplanar neighbours sit.
  auto reaches_inside_of = [&](uint32_t f, const std::array<Vec, 3>& cf) {
    const double magnitude = std::max({cf[0].cwiseAbs().maxCoeff(), cf[1].cwiseAbs().maxCoeff(),
                                       cf[2].cwiseAbs().maxCoeff(), (cf[1] - cf[0]).norm(), (cf[2] - cf[0]).norm()});
    return [&, n = normals[f], origin = cf[0], tolerance = 1e-5 * magnitude](uint32_t g) {
      if (normals[g].isZero()) return false;  // never hit
      const auto cg = corners(g);
      return std::min({n.dot(cg[0] - origin), n.dot(cg[1] - origin), n.dot(cg[2] - origin)}) < -tolerance;
    };
  };

  // The rings: tested at run time by their planes.
  {
    std::vector<uint32_t> seen(nt, UINT32_MAX);
    for (uint32_t f = 0; f < nt; ++f) {
      guard.ring_first[f] = uint32_t(guard.ring.size());
      if (normals[f].isZero()) continue;  // zero area: never a face a contact leaves through
      const auto reaches_inside = reaches_inside_of(f, corners(f));
      seen[f] = f;
      for (uint32_t v : triangles[f])
        for (uint32_t k = fan_first[v]; k < fan_first[v + 1]; ++k) {
          const uint32_t g = fan[k];
          if (seen[g] == f) continue;
          seen[g] = f;
          if (reaches_inside(g)) guard.ring.push_back(int32_t(g));
        }
    }
    guard.ring_first[nt] = uint32_t(guard.ring.size());
  }

  // Beyond the ring: the nearest face reaching inside, in growing shells of
  // cells, each thread marking what it has looked at.
  tbb::enumerable_thread_specific<std::vector<uint32_t>> marks([nt] { return std::vector<uint32_t>(nt, UINT32_MAX); });
  for_each_index(nt, nt >= 256, [&](size_t i) {
    const uint32_t f = uint32_t(i);
    if (normals[f].isZero()) return;
    std::vector<uint32_t>& seen = marks.local();
    const auto cf = corners(f);
    const auto reaches_inside = reaches_inside_of(f, cf);
    seen[f] = f;
    for (uint32_t k = guard.ring_first[f]; k < guard.ring_first[f + 1]; ++k) seen[uint32_t(guard.ring[k])] = f;
    std::array<int64_t, 3> a, b;
    box_cells(cf, a, b);
    double best = kShells * h;
    for (int shell = 0; shell <= kShells && best > (shell - 1) * h; ++shell) {
      for (int64_t z = std::max<int64_t>(0, a[2] - shell); z <= std::min(dims[2] - 1, b[2] + shell); ++z)
        for (int64_t y = std::max<int64_t>(0, a[1] - shell); y <= std::min(dims[1] - 1, b[1] + shell); ++y)
          for (int64_t x = std::max<int64_t>(0, a[0] - shell); x <= std::min(dims[0] - 1, b[0] + shell); ++x) {
            const bool searched = shell > 0 && x > a[0] - shell && x < b[0] + shell && y > a[1] - shell &&
                                  y < b[1] + shell && z > a[2] - shell && z < b[2] + shell;
            if (searched) continue;  // an earlier shell's cell
            const size_t cell = index(x, y, z);
            for (uint32_t k = first[cell]; k < first[cell + 1]; ++k) {
              const uint32_t g = members[k];
              if (seen[g] == f) continue;
              seen[g] = f;
              if ((centre[g] - centre[f]).norm() - bound[g] - bound[f] >= best) continue;
              if (reaches_inside(g)) best = std::min(best, triangle_distance(cf, corners(g)));
            }
          }
    }
    // Rounded down, so that a float distance below it is below the exact one.
    const float c = float(best);
    guard.faces[f].clearance = double(c) > best ? std::nextafter(c, 0.0f) : c;
  });
  return guard;
}

}  // namespace rtcd
