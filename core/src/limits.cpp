// Per-pair limits derived from the scene (the rules are in limits.hpp).
#include "rtcd/limits.hpp"

#include <algorithm>
#include <cmath>
#include <vector>

#include "rtcd/kernel/locate.h"

namespace rtcd {
namespace {

// Distance along the ray to the nearest triangle not touching vertex
// `skip`, through the kernel's ray/triangle location; infinity when nothing
// is met ahead.
double self_ray_length(const Mesh& mesh, uint32_t skip, const rtcd_ray& ray) {
  float best = std::numeric_limits<float>::infinity();
  const auto p = mesh.positions();
  auto v = [&](uint32_t i) { return rtcd_v3(p[i].x(), p[i].y(), p[i].z()); };
  for (const Mesh::Triangle& tri : mesh.triangles()) {
    if (tri[0] == skip || tri[1] == skip || tri[2] == skip) continue;
    const rtcd_location loc = rtcd_locate(&ray, v(tri[0]), v(tri[1]), v(tri[2]));
    if (loc.inside && loc.t_num > 0.0f) best = std::min(best, loc.t_num / loc.det);
  }
  return best;
}

ShapeScale measure_mesh(const Mesh& mesh, const RaySources& sources, double radius) {
  ShapeScale scale;
  scale.radius = radius;
  double edges = 0.0;
  const auto positions = mesh.positions();
  for (const Mesh::Triangle& tri : mesh.triangles())
    for (int k = 0; k < 3; ++k) edges += (positions[tri[(k + 1) % 3]] - positions[tri[k]]).cast<double>().norm();
  scale.edge = edges / (3.0 * double(mesh.triangle_count()));
  scale.triangles = uint32_t(mesh.triangle_count());

  const size_t vertices = sources.origins.size();
  const size_t samples = std::min<size_t>(vertices, 256);
  std::vector<double> lengths;
  for (size_t k = 0; k < samples; ++k) {
    const uint32_t v = uint32_t(k * vertices / samples);
    if (sources.directions[v].isZero()) continue;
    const Eigen::Vector3f d = sources.directions[v].normalized();
    const rtcd_vec3 origin = rtcd_v3(sources.origins[v].x(), sources.origins[v].y(), sources.origins[v].z());
    const double t = self_ray_length(mesh, v, rtcd_make_ray(origin, rtcd_v3(d.x(), d.y(), d.z())));
    if (std::isfinite(t)) lengths.push_back(t);
  }
  if (lengths.empty()) {
    scale.thickness = 2.0 * radius;  // open or degenerate: no ray leaves it
  } else {
    const auto tenth = lengths.begin() + ptrdiff_t(lengths.size() / 10);
    std::nth_element(lengths.begin(), tenth, lengths.end());
    scale.thickness = *tenth;
  }
  return scale;
}

}  // namespace

ShapeScale measure_scale(const Shape& shape) {
  if (const Mesh* mesh = shape.mesh()) return measure_mesh(*mesh, shape.sources(), shape.radius());
  ShapeScale scale;
  scale.radius = shape.radius();
  if (const auto* sphere = std::get_if<Sphere>(&shape.geometry())) scale.thickness = 2.0 * sphere->radius;
  if (const auto* box = std::get_if<Box>(&shape.geometry())) scale.thickness = 2.0 * box->half_extents.minCoeff();
  return scale;
}

rtcd_shape_scale to_kernel(const ShapeScale& s) { return {s.radius, s.thickness, s.edge, s.triangles, 0}; }

rtcd_limit_settings limit_settings(const Config& config) {
  rtcd_limit_settings c{};
  if (config.displacement_threshold) {
    c.displacement_threshold = *config.displacement_threshold;
    c.set |= RTCD_LIMIT_THRESHOLD;
  }
  if (config.distance_extension) {
    c.distance_extension = *config.distance_extension;
    c.set |= RTCD_LIMIT_EXTENSION;
  }
  if (config.max_walk_steps) {
    c.max_walk_steps = *config.max_walk_steps;
    c.set |= RTCD_LIMIT_WALK;
  }
  return c;
}

PairLimits derive_limits(const rtcd_limit_settings& settings, const ShapeScale& a, const ShapeScale& b,
                         double motion) {
  const rtcd_shape_scale sa = to_kernel(a), sb = to_kernel(b);
  const rtcd_pair_limits l = rtcd_derive_limits(&settings, &sa, &sb, motion);
  return {l.displacement_threshold, l.distance_extension, l.max_walk_steps};
}

}  // namespace rtcd
