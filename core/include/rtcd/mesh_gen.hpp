// Deterministic mesh generators: the one library of shapes that data/,
// tests, benchmarks and fuzzers all draw from. Every generator returns a
// valid closed (or, where named, open) mesh with vertices numbered in order
// of first use by the triangles, so save_obj + Mesh::load is the identity.
#pragma once

#include <array>
#include <cstdint>
#include <span>

#include <Eigen/Core>

#include "rtcd/export.hpp"
#include "rtcd/mesh.hpp"

namespace rtcd::gen {
RTCD_PUBLIC_BEGIN

Mesh box(const Eigen::Vector3d& half_extents);
// Icosahedron subdivided `level` times, projected on the sphere:
// 10 * 4^level + 2 vertices.
Mesh icosphere(double radius, int level);
Mesh torus(double major_radius, double minor_radius, int major_segments, int minor_segments);
// The thesis' concave mesh class: a genus-0 star-shaped body with dents and
// bumps, exactly `triangles` triangles (even, >= 8) and triangles / 2 + 2
// vertices, of radius about `radius`. Different seeds give different bodies.
Mesh concave_blob(int triangles, uint32_t seed, double radius = 1.0);
// An open wavy sheet of n x n quads over [-size/2, size/2]^2 (boundary edges).
Mesh open_sheet(int n, double size, double amplitude);
// A U-shaped prism: two arms along +y joined by a bar, 3 x 3 x 2*half_depth
// scaled by `scale`, centred at the origin. Its opening is
// [-0.5, 0.5] x [-0.5, 1.5] (times scale) in x, y.
Mesh u_shape(double scale = 1.0, double half_depth = 0.5);
// Regular polyhedra of circumradius `radius`: 4 and 8 triangles.
Mesh tetrahedron(double radius);
Mesh octahedron(double radius);
// A tube of radius `tube_radius` along the (p, q) torus knot (p turns
// around the axis, q through the hole; (2, 3) is the trefoil) on a torus
// of major radius `radius` and minor radius radius / 2: `segments` rings
// of `sides` vertices, 2 * segments * sides triangles. Throws UsageError
// when p and q are not coprime or the tube would cut itself.
Mesh torus_knot(int p, int q, double radius, double tube_radius, int segments, int sides);
// A spur gear: `teeth` trapezoidal teeth between root_radius and
// tip_radius, extruded to +-half_thickness along z; 16 * teeth triangles.
Mesh gear(int teeth, double root_radius, double tip_radius, double half_thickness);
// The union of unit cubes at `cells` (integer coordinates), each side
// `cell` long, centred on their bounds: two triangles per exposed face.
// Throws UsageError where cells meet along an edge or at a corner only
// (the surface would not be a manifold there).
Mesh voxels(std::span<const std::array<int, 3>> cells, double cell);
// A branching body from voxels: a trunk with three arms (a cactus),
// `height` tall.
Mesh cactus(double height);

// Renumbers vertices by first use (see above) and builds the mesh.
Mesh in_first_use_order(std::span<const Eigen::Vector3f> positions, std::span<const Mesh::Triangle> triangles,
                        MeshOptions options = {});

RTCD_PUBLIC_END
}  // namespace rtcd::gen
