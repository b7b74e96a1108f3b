// Family shapes and random poses (see families.hpp).
#include "rtcd/validation/families.hpp"

#include <cmath>
#include <numbers>

#include "rtcd/criterion.hpp"
#include "rtcd/error.hpp"
#include "rtcd/mesh_gen.hpp"

namespace rtcd::validation {
namespace {

// Uniform in [0, 1) from mt19937_64's raw output, which the standard fixes
// (distributions are implementation-defined), so poses replay anywhere.
double unit(std::mt19937_64& g) { return double(g() >> 11) * 0x1.0p-53; }

Eigen::Vector3d unit_vector(std::mt19937_64& g) {
  const double z = 2 * unit(g) - 1, phi = 2 * std::numbers::pi * unit(g), r = std::sqrt(1 - z * z);
  return {r * std::cos(phi), r * std::sin(phi), z};
}

// Uniform over rotations (Shoemake).
Eigen::Quaterniond random_rotation(std::mt19937_64& g) {
  const double u1 = unit(g), u2 = 2 * std::numbers::pi * unit(g), u3 = 2 * std::numbers::pi * unit(g);
  const double s1 = std::sqrt(1 - u1), s2 = std::sqrt(u1);
  return Eigen::Quaterniond(s2 * std::cos(u3), s1 * std::sin(u2), s1 * std::cos(u2), s2 * std::sin(u3));
}

std::mt19937_64 generator(uint64_t seed, uint64_t index, uint64_t stream) {
  std::seed_seq seq{uint32_t(seed), uint32_t(seed >> 32), uint32_t(index), uint32_t(index >> 32), uint32_t(stream)};
  return std::mt19937_64(seq);
}

std::shared_ptr<const Shape> mesh(Mesh m) { return std::make_shared<Shape>(std::move(m)); }

}  // namespace

const std::vector<std::string>& family_names() {
  static const std::vector<std::string> names = {"convex", "concave", "torus",  "plates", "highres", "primitives",
                                                   "bars",   "rings",   "knots",  "gears",  "coarse",  "boxes",
                                                   "cacti",  "sheets",  "tiny",   "ratio"};
  return names;
}

Family make_family(const std::string& name) {
  Family f;
  f.name = name;
  if (name == "convex") {
    f.description = "box mesh (half 0.4) vs icosphere mesh (r 1, 1280 triangles)";
    f.a = mesh(gen::box({0.4, 0.4, 0.4}));
    f.b = mesh(gen::icosphere(1.0, 3));
    f.convex = true;
    f.reach = 2.2;
  } else if (name == "concave") {
    f.description = "two 902-triangle concave blobs (r 0.6 and 1)";
    f.a = mesh(gen::concave_blob(902, 11, 0.6));
    f.b = mesh(gen::concave_blob(902, 12, 1.0));
    f.reach = 2.2;
  } else if (name == "torus") {
    f.description = "torus (R 0.5, r 0.18) vs torus (R 1, r 0.35)";
    f.a = mesh(gen::torus(0.5, 0.18, 32, 16));
    f.b = mesh(gen::torus(1.0, 0.35, 48, 24));
    f.reach = 1.9;
    f.thinnest = 0.36;
  } else if (name == "plates") {
    f.description = "902-triangle concave blob (r 0.6) vs thin plate (2 x 2 x 0.04)";
    f.a = mesh(gen::concave_blob(902, 13, 0.6));
    f.b = mesh(gen::box({1.0, 1.0, 0.02}));
    f.reach = 1.8;
    f.thinnest = 0.04;
  } else if (name == "highres") {
    f.description = "902-triangle concave blob (r 0.6) vs 20000-triangle concave blob (r 1)";
    f.a = mesh(gen::concave_blob(902, 14, 0.6));
    f.b = mesh(gen::concave_blob(20000, 15, 1.0));
    f.reach = 2.2;
  } else if (name == "primitives") {
    f.description = "box volume (0.3 x 0.4 x 0.5 half) vs sphere volume (r 1)";
    f.a = std::make_shared<Shape>(Box{{0.3, 0.4, 0.5}});
    f.b = std::make_shared<Shape>(Sphere{1.0});
    f.convex = true;
    f.reach = 2.2;
  } else if (name == "bars") {
    // Thin bodies crossing at random: most overlaps have no vertex inside.
    f.description = "bar mesh (1 x 0.08 x 0.08) vs plank mesh (1 x 0.2 x 0.04), crossing";
    f.a = mesh(gen::box({0.5, 0.04, 0.04}));
    f.b = mesh(gen::box({0.5, 0.1, 0.02}));
    f.convex = true;
    f.reach = 0.4;
    f.thinnest = 0.04;
  } else if (name == "rings") {
    f.description = "ring (torus R 0.5, r 0.05, 768 triangles) vs peg mesh (0.08 x 0.08 x 1.2)";
    f.a = mesh(gen::torus(0.5, 0.05, 48, 8));
    f.b = mesh(gen::box({0.04, 0.04, 0.6}));
    f.reach = 0.6;
    f.thinnest = 0.08;
  } else if (name == "knots") {
    // A thin tube's inward rays cross the tube and leave the blob far beyond:
    // the family where the ray's depth and the true penetration part.
    f.description = "trefoil-knot tube (tube r 0.06, 6400 triangles) vs 4050-triangle concave blob (r 1)";
    f.a = mesh(gen::torus_knot(2, 3, 0.45, 0.06, 200, 16));
    f.b = mesh(gen::concave_blob(4050, 16, 1.0));
    f.reach = 2.6;
    f.thinnest = 0.12;
  } else if (name == "gears") {
    f.description = "12-tooth gear (r 0.6, 0.2 thick) vs 16-tooth gear (r 1, 0.3 thick)";
    f.a = mesh(gen::gear(12, 0.45, 0.6, 0.1));
    f.b = mesh(gen::gear(16, 0.8, 1.0, 0.15));
    f.reach = 1.7;
    f.thinnest = 0.08;
  } else if (name == "coarse") {
    f.description = "tetrahedron (r 0.7, 4 triangles) vs octahedron (r 1, 8 triangles)";
    f.a = mesh(gen::tetrahedron(0.7));
    f.b = mesh(gen::octahedron(1.0));
    f.convex = true;
    f.reach = 1.7;
    f.thinnest = 0.23;
  } else if (name == "boxes") {
    f.description = "box mesh (half 0.3, 12 triangles) vs slab mesh (1.2 x 1.2 x 0.3, 12 triangles)";
    f.a = mesh(gen::box({0.3, 0.3, 0.3}));
    f.b = mesh(gen::box({0.6, 0.6, 0.15}));
    f.convex = true;
    f.reach = 1.2;
    f.thinnest = 0.3;
  } else if (name == "cacti") {
    f.description = "voxel cactus (a trunk with three arms, 1.2 tall) vs 902-triangle concave blob (r 1)";
    f.a = mesh(gen::cactus(1.2));
    f.b = mesh(gen::concave_blob(902, 17, 1.0));
    f.reach = 1.9;
    f.thinnest = 0.17;
  } else if (name == "sheets") {
    // The distance bound's coarse cases: the sheet is thinner than a cell of
    // either grid, its edges longer than the blob's cells, its rims blades.
    f.description = "902-triangle concave blob (r 0.6) vs sheet mesh (2 x 2 x 0.002, 12 triangles)";
    f.a = mesh(gen::concave_blob(902, 18, 0.6));
    f.b = mesh(gen::box({1.0, 1.0, 0.001}));
    f.reach = 1.8;
    f.thinnest = 0.002;
    f.motion = 1e-4;
  } else if (name == "tiny") {
    f.description = "two 902-triangle concave blobs 1e-9 across (r 3e-10 and 5e-10)";
    f.a = mesh(gen::concave_blob(902, 19, 3e-10));
    f.b = mesh(gen::concave_blob(902, 20, 5e-10));
    f.reach = 1.1e-9;
    f.thinnest = 1e-10;
  } else if (name == "ratio") {
    f.description = "902-triangle concave blob (r 1e-4) at the surface of a 902-triangle concave blob (r 1)";
    f.a = mesh(gen::concave_blob(902, 21, 1e-4));
    f.b = mesh(gen::concave_blob(902, 22, 1.0));
    f.at_surface = true;
    f.thinnest = 1e-4;
    f.motion = 5e-7;
  } else {
    std::string list;
    for (const auto& n : family_names()) list += (list.empty() ? "" : ", ") + n;
    throw UsageError("unknown family '" + name + "' (families: " + list + ")");
  }
  return f;
}

double Family::iterative_threshold() const {
  return std::min(0.01 * std::max(a->radius(), b->radius()), 0.1 * thinnest);
}

double Family::step_motion() const { return motion > 0 ? motion : 0.005 * std::max(a->radius(), b->radius()); }

PosePair random_poses(const Family& family, uint64_t seed, uint64_t index) {
  auto g = generator(seed, index, 0);
  PosePair p;
  const Eigen::Vector3d centre =
      family.origin + 2.0 * family.reach * Eigen::Vector3d(unit(g) - 0.5, unit(g) - 0.5, unit(g) - 0.5);
  p.a.orientation = random_rotation(g);
  p.b.orientation = random_rotation(g);
  p.a.position = centre;
  if (!family.at_surface) {
    p.b.position = centre + family.reach * unit(g) * unit_vector(g);
    return p;
  }
  const Mesh& m = *family.b->mesh();
  const auto corners = [&](const Mesh::Triangle& t) {
    return std::array<Eigen::Vector3d, 3>{m.positions()[t[0]].cast<double>(), m.positions()[t[1]].cast<double>(),
                                          m.positions()[t[2]].cast<double>()};
  };
  double area = 0.0;
  for (const Mesh::Triangle& t : m.triangles()) {
    const auto c = corners(t);
    area += (c[1] - c[0]).cross(c[2] - c[0]).norm();
  }
  double pick = unit(g) * area;
  size_t k = 0;
  for (; k + 1 < m.triangles().size(); ++k) {
    const auto c = corners(m.triangles()[k]);
    pick -= (c[1] - c[0]).cross(c[2] - c[0]).norm();
    if (pick < 0) break;
  }
  const auto c = corners(m.triangles()[k]);
  const double r1 = std::sqrt(unit(g)), r2 = unit(g);  // uniform over the triangle
  const Eigen::Vector3d on = (1 - r1) * c[0] + r1 * (1 - r2) * c[1] + r1 * r2 * c[2];
  const Eigen::Vector3d normal = (c[1] - c[0]).cross(c[2] - c[0]).normalized();
  const Eigen::Vector3d local = on + (4 * unit(g) - 2) * family.a->radius() * normal;
  p.b.position = centre - p.b.orientation * local;
  return p;
}

PosePair moved(const Family& family, const PosePair& poses, double displacement, uint64_t seed, uint64_t index) {
  auto g = generator(seed, index, 1);
  // Split the budget between a translation and a rotation about B's centre,
  // then shrink until equation 2.1 (on the larger radius) is within it.
  const double radius = std::max(family.a->radius(), family.b->radius());
  PosePair p = poses;
  const Eigen::Vector3d shift = unit_vector(g) * unit(g);
  const Eigen::Vector3d axis = unit_vector(g);
  const double turn = unit(g);
  for (double scale = displacement; scale > 0; scale *= 0.5) {
    p.b.position = poses.b.position + 0.5 * scale * shift;
    p.b.orientation = (Eigen::AngleAxisd(0.5 * scale * turn / radius, axis) * poses.b.orientation).normalized();
    const Pose before = poses.b.inverse() * poses.a, after = p.b.inverse() * p.a;
    if (max_displacement(before, after, radius) <= displacement) break;
  }
  return p;
}

}  // namespace rtcd::validation
