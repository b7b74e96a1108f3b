// Deterministic mesh generators (see mesh_gen.hpp).
#include "rtcd/mesh_gen.hpp"

#include <cmath>
#include <map>
#include <numeric>
#include <set>
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

// The triangles of a tube closed on itself: `rings` rings of `sides`
// vertices each, ring after ring (torus, knot), two triangles per quad.
std::vector<Tri> closed_tube(int rings, int sides) {
  std::vector<Tri> t;
  auto at = [&](int i, int j) { return uint32_t((i % rings) * sides + (j % sides)); };
  for (int i = 0; i < rings; ++i)
    for (int j = 0; j < sides; ++j) {
      t.push_back({at(i, j), at(i + 1, j), at(i + 1, j + 1)});
      t.push_back({at(i, j), at(i + 1, j + 1), at(i, j + 1)});
    }
  return t;
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
  for (int i = 0; i < nu; ++i) {
    const double u = 2 * pi * i / nu;
    for (int j = 0; j < nv; ++j) {
      const double v = 2 * pi * j / nv;
      const double r = major_radius + minor_radius * std::cos(v);
      p.emplace_back(r * std::cos(u), r * std::sin(u), minor_radius * std::sin(v));
    }
  }
  return make(p, closed_tube(nu, nv));
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

// Each triangle of a body star-shaped about the origin turned to face away
// from it.
Mesh facing_out(const std::vector<Eigen::Vector3d>& p, std::vector<Tri> t) {
  for (Tri& tri : t)
    if ((p[tri[1]] - p[tri[0]]).cross(p[tri[2]] - p[tri[0]]).dot(p[tri[0]] + p[tri[1]] + p[tri[2]]) < 0)
      std::swap(tri[1], tri[2]);
  return make(p, t);
}

Mesh tetrahedron(double radius) {
  const double k = radius / std::sqrt(3.0);
  const std::vector<Eigen::Vector3d> p = {{k, k, k}, {k, -k, -k}, {-k, k, -k}, {-k, -k, k}};
  return facing_out(p, {{0, 1, 2}, {0, 1, 3}, {0, 2, 3}, {1, 2, 3}});
}

Mesh octahedron(double radius) {
  const std::vector<Eigen::Vector3d> p = {{radius, 0, 0}, {-radius, 0, 0}, {0, radius, 0},
                                          {0, -radius, 0}, {0, 0, radius}, {0, 0, -radius}};
  std::vector<Tri> t;
  for (uint32_t x : {0u, 1u})
    for (uint32_t y : {2u, 3u})
      for (uint32_t z : {4u, 5u}) t.push_back({x, y, z});
  return facing_out(p, t);
}

Mesh torus_knot(int pk, int qk, double radius, double tube_radius, int segments, int sides) {
  if (pk < 1 || qk < 1 || std::gcd(pk, qk) != 1 || segments < 3 || sides < 3 || !(tube_radius > 0) || !(radius > 0))
    throw UsageError("torus_knot needs coprime p, q >= 1, >= 3 segments and sides, and positive radii");
  const double minor = 0.5 * radius;
  auto curve = [&](double s) {
    const double r = radius + minor * std::cos(qk * s);
    return Eigen::Vector3d(r * std::cos(pk * s), r * std::sin(pk * s), minor * std::sin(qk * s));
  };
  // Frenet frames from central differences: a torus knot's curvature never
  // vanishes, and the frames close up with the curve (no seam).
  const double h = 1e-4;
  std::vector<Eigen::Vector3d> centre(segments), normal(segments), binormal(segments);
  for (int i = 0; i < segments; ++i) {
    const double s = 2 * pi * i / segments;
    const Eigen::Vector3d c = curve(s), d1 = (curve(s + h) - curve(s - h)) / (2 * h);
    const Eigen::Vector3d d2 = (curve(s + h) - 2 * c + curve(s - h)) / (h * h);
    const Eigen::Vector3d tangent = d1.normalized();
    centre[i] = c;
    normal[i] = (d2 - d2.dot(tangent) * tangent).normalized();
    binormal[i] = tangent.cross(normal[i]);
  }
  // The tube must not meet itself: the curve's points farther apart along it
  // than the tube's girth stay more than a diameter apart.
  const double step = 2 * pi / segments;
  for (int i = 0; i < segments; ++i)
    for (int j = i + 1; j < segments; ++j) {
      const int apart = std::min(j - i, segments - (j - i));
      if (apart * step * radius > 4 * tube_radius && (centre[i] - centre[j]).norm() < 2.2 * tube_radius)
        throw UsageError("torus_knot: the tube is too thick for its knot and would cut itself");
    }
  std::vector<Eigen::Vector3d> p;
  for (int i = 0; i < segments; ++i)
    for (int j = 0; j < sides; ++j) {
      const double v = 2 * pi * j / sides;
      // cos v * N - sin v * B runs the way that makes the triangles below face out.
      p.push_back(centre[i] + tube_radius * (std::cos(v) * normal[i] - std::sin(v) * binormal[i]));
    }
  return make(p, closed_tube(segments, sides));
}

Mesh gear(int teeth, double root_radius, double tip_radius, double half_thickness) {
  if (teeth < 3 || !(root_radius > 0) || !(tip_radius > root_radius) || !(half_thickness > 0))
    throw UsageError("gear needs >= 3 teeth, tip_radius > root_radius > 0 and a positive thickness");
  // The outline, counter-clockwise: per tooth a root, two tip corners and a root.
  std::vector<Eigen::Vector2d> outline;
  const double fractions[4] = {0.0, 0.25, 0.5, 0.75}, radii[4] = {root_radius, tip_radius, tip_radius, root_radius};
  for (int k = 0; k < teeth; ++k)
    for (int c = 0; c < 4; ++c) {
      const double a = 2 * pi * (k + fractions[c]) / teeth;
      outline.emplace_back(radii[c] * std::cos(a), radii[c] * std::sin(a));
    }
  const uint32_t n = uint32_t(outline.size());
  std::vector<Eigen::Vector3d> p;
  for (double z : {-half_thickness, half_thickness})
    for (const auto& o : outline) p.emplace_back(o.x(), o.y(), z);
  p.emplace_back(0, 0, -half_thickness);
  p.emplace_back(0, 0, half_thickness);
  const uint32_t bottom = 2 * n, top = 2 * n + 1;
  std::vector<Tri> t;
  for (uint32_t i = 0; i < n; ++i) {
    const uint32_t j = (i + 1) % n;
    t.push_back({top, i + n, j + n});  // the outline is star-shaped about the axis: fans
    t.push_back({bottom, j, i});
    t.push_back({i, j, j + n});
    t.push_back({i, j + n, i + n});
  }
  return make(p, t);
}

Mesh voxels(std::span<const std::array<int, 3>> cells, double cell) {
  if (cells.empty() || !(cell > 0)) throw UsageError("voxels needs at least one cell and a positive cell size");
  std::set<std::array<int, 3>> filled(cells.begin(), cells.end());
  auto has = [&](int x, int y, int z) { return filled.count({x, y, z}) > 0; };
  // Cells that share an edge (or a corner) and no face with anything
  // filled between them pinch the surface.
  for (const auto& c : filled)
    for (int dx = -1; dx <= 1; ++dx)
      for (int dy = -1; dy <= 1; ++dy)
        for (int dz = -1; dz <= 1; ++dz) {
          if (std::abs(dx) + std::abs(dy) + std::abs(dz) < 2 || !has(c[0] + dx, c[1] + dy, c[2] + dz)) continue;
          // Some path of face steps inside the cube spanned by the two cells.
          const bool joined = (dx && has(c[0] + dx, c[1], c[2]) && (has(c[0] + dx, c[1] + dy, c[2]) || has(c[0] + dx, c[1], c[2] + dz))) ||
                              (dy && has(c[0], c[1] + dy, c[2]) && (has(c[0] + dx, c[1] + dy, c[2]) || has(c[0], c[1] + dy, c[2] + dz))) ||
                              (dz && has(c[0], c[1], c[2] + dz) && (has(c[0] + dx, c[1], c[2] + dz) || has(c[0], c[1] + dy, c[2] + dz)));
          if (!joined)
            throw UsageError("voxels: cells meet along an edge or at a corner only");
        }
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(1e300), hi = -lo;
  for (const auto& c : filled)
    for (int k = 0; k < 3; ++k) lo[k] = std::min(lo[k], double(c[k])), hi[k] = std::max(hi[k], double(c[k] + 1));
  const Eigen::Vector3d middle = 0.5 * (lo + hi);
  std::map<std::array<int, 3>, uint32_t> corner_ids;
  std::vector<Eigen::Vector3d> p;
  auto corner = [&](int x, int y, int z) {
    auto [it, inserted] = corner_ids.try_emplace({x, y, z}, uint32_t(p.size()));
    if (inserted) p.push_back(cell * (Eigen::Vector3d(x, y, z) - middle));
    return it->second;
  };
  // The faces of box(), each with the neighbour behind it: +x, -x, +y, -y, +z, -z.
  const int faces[6][4] = {{1, 3, 7, 5}, {0, 4, 6, 2}, {2, 6, 7, 3}, {0, 1, 5, 4}, {4, 5, 7, 6}, {0, 2, 3, 1}};
  const int behind[6][3] = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
  std::vector<Tri> t;
  for (const auto& c : filled)
    for (int f = 0; f < 6; ++f) {
      if (has(c[0] + behind[f][0], c[1] + behind[f][1], c[2] + behind[f][2])) continue;
      uint32_t q[4];
      for (int k = 0; k < 4; ++k) {
        const int i = faces[f][k];
        q[k] = corner(c[0] + (i & 1), c[1] + ((i >> 1) & 1), c[2] + ((i >> 2) & 1));
      }
      t.push_back({q[0], q[1], q[2]});
      t.push_back({q[0], q[2], q[3]});
    }
  return make(p, t);
}

Mesh cactus(double height) {
  const std::array<int, 3> cells[] = {
      {0, 0, 0},  {0, 0, 1},  {0, 0, 2},  {0, 0, 3},  {0, 0, 4},  {0, 0, 5},  {0, 0, 6},   // the trunk
      {-1, 0, 2}, {-2, 0, 2}, {-2, 0, 3}, {-2, 0, 4},                                    // left arm
      {1, 0, 3},  {2, 0, 3},  {2, 0, 4},  {2, 0, 5},                                     // right arm
      {0, -1, 1}, {0, -2, 1}, {0, -2, 2}, {0, -2, 3}};                                   // front arm
  return voxels(cells, height / 7.0);
}

}  // namespace rtcd::gen
