// Deterministic mesh generators (see mesh_gen.hpp).
#include "rtcd/mesh_gen.hpp"

#include <cmath>
#include <map>
#include <numbers>
#include <random>
#include <stdexcept>

#include "rtcd/error.hpp"

namespace rtcd::gen {
namespace {

using Tri = Mesh::Triangle;
constexpr double pi = std::numbers::pi;

// Uniform in [0, 1) from mt19937's raw output, which the standard fixes
// (distributions are implementation-defined, so not used here).
double unit(std::mt19937& g) { return g() / 4294967296.0; }

Mesh make(const std::vector<Eigen::Vector3d>& p, const std::vector<Tri>& t) {
  std::vector<Eigen::Vector3f> pf;
  pf.reserve(p.size());
  // Coordinates that are zero up to rounding (cos(pi / 2)) are stored as
  // zero: they then round-trip through any text format.
  for (const auto& v : p) pf.push_back(v.unaryExpr([](double c) { return std::abs(c) < 1e-12 ? 0.0 : c; }).cast<float>());
  return in_first_use_order(pf, t);
}

// Unit sphere as a latitude/longitude grid: `segments` around, `rings`
// interior latitude circles, plus two poles.
void uv_sphere(int segments, int rings, std::vector<Eigen::Vector3d>& p, std::vector<Tri>& t) {
  p.clear();
  t.clear();
  p.emplace_back(0, 0, 1);
  for (int r = 1; r <= rings; ++r) {
    const double theta = pi * r / (rings + 1);
    for (int s = 0; s < segments; ++s) {
      const double phi = 2 * pi * s / segments;
      p.emplace_back(std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi), std::cos(theta));
    }
  }
  p.emplace_back(0, 0, -1);
  const uint32_t south = uint32_t(p.size() - 1);
  auto at = [&](int r, int s) { return uint32_t(1 + (r - 1) * segments + (s % segments)); };
  for (int s = 0; s < segments; ++s) t.push_back({0, at(1, s), at(1, s + 1)});
  for (int r = 1; r < rings; ++r)
    for (int s = 0; s < segments; ++s) {
      t.push_back({at(r, s), at(r + 1, s), at(r + 1, s + 1)});
      t.push_back({at(r, s), at(r + 1, s + 1), at(r, s + 1)});
    }
  for (int s = 0; s < segments; ++s) t.push_back({south, at(rings, s + 1), at(rings, s)});
}

// Splits the longest edge (on the unit sphere): +1 vertex, +2 triangles.
void split_longest_edge(std::vector<Eigen::Vector3d>& p, std::vector<Tri>& t) {
  double best = -1;
  uint32_t ea = 0, eb = 0;
  for (const Tri& tri : t)
    for (int k = 0; k < 3; ++k) {
      const uint32_t a = tri[k], b = tri[(k + 1) % 3];
      const double len = (p[a] - p[b]).squaredNorm();
      if (len > best + 1e-12 || (std::abs(len - best) <= 1e-12 && std::min(a, b) < std::min(ea, eb))) {
        best = len;
        ea = a;
        eb = b;
      }
    }
  const uint32_t m = uint32_t(p.size());
  p.push_back((0.5 * (p[ea] + p[eb])).normalized());
  const size_t n = t.size();
  for (size_t i = 0; i < n; ++i)
    for (int k = 0; k < 3; ++k) {
      const uint32_t a = t[i][k], b = t[i][(k + 1) % 3], c = t[i][(k + 2) % 3];
      if ((a == ea && b == eb) || (a == eb && b == ea)) {
        t[i] = {a, m, c};
        t.push_back({m, b, c});
        break;
      }
    }
}

}  // namespace

Mesh in_first_use_order(std::span<const Eigen::Vector3f> positions, std::span<const Mesh::Triangle> triangles,
                        MeshOptions options) {
  std::vector<int64_t> new_index(positions.size(), -1);
  std::vector<Eigen::Vector3f> p;
  std::vector<Tri> t(triangles.begin(), triangles.end());
  for (Tri& tri : t)
    for (uint32_t& v : tri) {
      if (v >= positions.size()) continue;  // left for validation to name
      if (new_index[v] < 0) {
        new_index[v] = int64_t(p.size());
        p.push_back(positions[v]);
      }
      v = uint32_t(new_index[v]);
    }
  return Mesh(std::move(p), std::move(t), options);
}

Mesh box(const Eigen::Vector3d& h) {
  std::vector<Eigen::Vector3d> p;
  for (int i = 0; i < 8; ++i) p.emplace_back(i & 1 ? h.x() : -h.x(), i & 2 ? h.y() : -h.y(), i & 4 ? h.z() : -h.z());
  // Each face as a quad (counter-clockwise from outside), split along one diagonal.
  const int faces[6][4] = {{1, 3, 7, 5}, {0, 4, 6, 2}, {2, 6, 7, 3}, {0, 1, 5, 4}, {4, 5, 7, 6}, {0, 2, 3, 1}};
  std::vector<Tri> t;
  for (const auto& f : faces) {
    t.push_back({uint32_t(f[0]), uint32_t(f[1]), uint32_t(f[2])});
    t.push_back({uint32_t(f[0]), uint32_t(f[2]), uint32_t(f[3])});
  }
  return make(p, t);
}

Mesh icosphere(double radius, int level) {
  if (level < 0 || level > 8) throw UsageError("icosphere level must lie in [0, 8]");
  const double g = (1 + std::sqrt(5.0)) / 2;
  std::vector<Eigen::Vector3d> p = {{-1, g, 0}, {1, g, 0}, {-1, -g, 0}, {1, -g, 0}, {0, -1, g}, {0, 1, g},
                                    {0, -1, -g}, {0, 1, -g}, {g, 0, -1}, {g, 0, 1}, {-g, 0, -1}, {-g, 0, 1}};
  for (auto& v : p) v.normalize();
  std::vector<Tri> t = {{0, 11, 5}, {0, 5, 1},  {0, 1, 7},   {0, 7, 10}, {0, 10, 11}, {1, 5, 9}, {5, 11, 4},
                        {11, 10, 2}, {10, 7, 6}, {7, 1, 8},  {3, 9, 4},  {3, 4, 2},   {3, 2, 6}, {3, 6, 8},
                        {3, 8, 9},  {4, 9, 5},  {2, 4, 11}, {6, 2, 10}, {8, 6, 7},   {9, 8, 1}};
  for (int l = 0; l < level; ++l) {
    std::map<std::pair<uint32_t, uint32_t>, uint32_t> mid;
    auto midpoint = [&](uint32_t a, uint32_t b) {
      auto key = std::minmax(a, b);
      auto [it, inserted] = mid.try_emplace({key.first, key.second}, uint32_t(p.size()));
      if (inserted) p.push_back((0.5 * (p[a] + p[b])).normalized());
      return it->second;
    };
    std::vector<Tri> next;
    for (const Tri& tri : t) {
      const uint32_t ab = midpoint(tri[0], tri[1]), bc = midpoint(tri[1], tri[2]), ca = midpoint(tri[2], tri[0]);
      next.push_back({tri[0], ab, ca});
      next.push_back({tri[1], bc, ab});
      next.push_back({tri[2], ca, bc});
      next.push_back({ab, bc, ca});
    }
    t = std::move(next);
  }
  for (auto& v : p) v *= radius;
  return make(p, t);
}

Mesh torus(double major_radius, double minor_radius, int nu, int nv) {
  if (nu < 3 || nv < 3 || !(minor_radius > 0) || !(major_radius > minor_radius))
    throw UsageError("torus needs >= 3 segments each way and major_radius > minor_radius > 0");
  std::vector<Eigen::Vector3d> p;
  std::vector<Tri> t;
  for (int i = 0; i < nu; ++i) {
    const double u = 2 * pi * i / nu;
    for (int j = 0; j < nv; ++j) {
      const double v = 2 * pi * j / nv;
      const double r = major_radius + minor_radius * std::cos(v);
      p.emplace_back(r * std::cos(u), r * std::sin(u), minor_radius * std::sin(v));
    }
  }
  auto at = [&](int i, int j) { return uint32_t((i % nu) * nv + (j % nv)); };
  for (int i = 0; i < nu; ++i)
    for (int j = 0; j < nv; ++j) {
      t.push_back({at(i, j), at(i + 1, j), at(i + 1, j + 1)});
      t.push_back({at(i, j), at(i + 1, j + 1), at(i, j + 1)});
    }
  return make(p, t);
}

Mesh concave_blob(int triangles, uint32_t seed, double radius) {
  if (triangles < 8 || triangles % 2 != 0) throw UsageError("concave_blob needs an even triangle count >= 8");
  // The largest latitude/longitude sphere with about twice as many segments
  // as rings that fits, then longest-edge splits up to the exact count.
  const int half = triangles / 2;
  int best_rings = 1, best_segments = 3;
  for (int rings = 1; 3 * rings <= half; ++rings) {
    const int segments = half / rings;
    if (segments < 3) break;
    const double aspect = std::abs(std::log(double(segments) / (2.0 * rings)));
    const int product = rings * segments, best_product = best_rings * best_segments;
    const double best_aspect = std::abs(std::log(double(best_segments) / (2.0 * best_rings)));
    if (product - 20 * aspect > best_product - 20 * best_aspect) {
      best_rings = rings;
      best_segments = segments;
    }
  }
  std::vector<Eigen::Vector3d> p;
  std::vector<Tri> t;
  uv_sphere(best_segments, best_rings, p, t);
  while (int(t.size()) < triangles) split_longest_edge(p, t);

  // Dents and bumps: a positive radial function keeps the body star-shaped,
  // so it stays genus 0 and free of self-intersection.
  std::mt19937 rng(seed);
  struct Bump {
    Eigen::Vector3d center;
    double amplitude, width;
  };
  std::vector<Bump> bumps;
  for (int i = 0; i < 7; ++i) {
    const double z = 2 * unit(rng) - 1, phi = 2 * pi * unit(rng);
    const double s = std::sqrt(1 - z * z);
    // Dents narrower than the body's curvature make it concave.
    const bool dent = i % 2 == 0;
    const double amplitude = dent ? -0.35 - 0.15 * unit(rng) : 0.15 + 0.15 * unit(rng);
    const double width = dent ? 0.35 + 0.1 * unit(rng) : 0.45 + 0.15 * unit(rng);
    bumps.push_back({{s * std::cos(phi), s * std::sin(phi), z}, amplitude, width});
  }
  for (auto& v : p) {
    double r = 1.0;
    for (const Bump& b : bumps) r += b.amplitude * std::exp(-(v - b.center).squaredNorm() / (2 * b.width * b.width));
    v *= radius * std::max(r, 0.3);
  }
  return make(p, t);
}

Mesh open_sheet(int n, double size, double amplitude) {
  if (n < 1) throw UsageError("open_sheet needs n >= 1");
  std::vector<Eigen::Vector3d> p;
  std::vector<Tri> t;
  for (int i = 0; i <= n; ++i)
    for (int j = 0; j <= n; ++j) {
      const double x = size * (double(i) / n - 0.5), y = size * (double(j) / n - 0.5);
      p.emplace_back(x, y, amplitude * std::sin(2 * pi * x / size) * std::cos(2 * pi * y / size));
    }
  auto at = [&](int i, int j) { return uint32_t(i * (n + 1) + j); };
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) {
      t.push_back({at(i, j), at(i + 1, j), at(i + 1, j + 1)});
      t.push_back({at(i, j), at(i + 1, j + 1), at(i, j + 1)});
    }
  return make(p, t);
}

Mesh u_shape(double scale, double half_depth) {
  // Outline counter-clockwise in x, y, centred so the opening is
  // [-0.5, 0.5] x [-0.5, 1.5].
  const double outline[8][2] = {{0, 0}, {3, 0}, {3, 3}, {2, 3}, {2, 1}, {1, 1}, {1, 3}, {0, 3}};
  const uint32_t cap[6][3] = {{0, 1, 4}, {0, 4, 5}, {1, 2, 3}, {1, 3, 4}, {0, 5, 6}, {0, 6, 7}};
  std::vector<Eigen::Vector3d> p;
  for (double z : {-half_depth, half_depth})
    for (const auto& o : outline) p.emplace_back(scale * (o[0] - 1.5), scale * (o[1] - 1.5), z);
  std::vector<Tri> t;
  for (const auto& c : cap) {
    t.push_back({c[0] + 8, c[1] + 8, c[2] + 8});  // top, seen from +z
    t.push_back({c[0], c[2], c[1]});              // bottom, reversed
  }
  for (uint32_t i = 0; i < 8; ++i) {
    const uint32_t j = (i + 1) % 8;
    t.push_back({i, j, j + 8});
    t.push_back({i, j + 8, i + 8});
  }
  return make(p, t);
}

}  // namespace rtcd::gen
