// Mass properties. A closed mesh's volume integrals come from the
// divergence theorem: every integral of a polynomial over the body becomes
// a sum over its triangles of a polynomial integrated over each triangle
// (Mirtich 1996; the triangle form follows Eberly, "Polyhedral Mass
// Properties").
#include "rtcd/sim/mass.hpp"

#include <array>
#include <cmath>
#include <numbers>
#include <sstream>
#include <string>

#include <Eigen/Eigenvalues>

#include "rtcd/error.hpp"

namespace rtcd::sim {
namespace {

// Integrals over the body of 1, x, y, z, x², y², z², xy, yz, zx: all that
// a rigid body's mass properties need at unit density.
struct VolumeIntegrals {
  double volume = 0;
  Eigen::Vector3d first = Eigen::Vector3d::Zero();     // ∫x, ∫y, ∫z
  Eigen::Vector3d squares = Eigen::Vector3d::Zero();   // ∫x², ∫y², ∫z²
  Eigen::Vector3d products = Eigen::Vector3d::Zero();  // ∫xy, ∫yz, ∫zx
};

// One coordinate's values w0, w1, w2 at a triangle's corners, and the
// complete homogeneous symmetric polynomials of them that integrating its
// powers over the triangle produces. With p(s, t) = p0 + s (p1 - p0) +
// t (p2 - p0) over the parameter triangle s, t >= 0, s + t <= 1:
//   ∫ w ds dt = h1 / 6,  ∫ w² ds dt = h2 / 12,  ∫ w³ ds dt = h3 / 20,
// and, for a second coordinate u, ∫ w² u ds dt = Σk u_k ∂h3/∂w_k / 60.
struct CornerPolynomials {
  double h1, h2, h3;
  std::array<double, 3> dh3;  // ∂h3/∂w_k = h2 + w_k h1 + w_k²

  CornerPolynomials(double w0, double w1, double w2) {
    h1 = w0 + w1 + w2;
    h2 = w0 * w0 + w1 * (w0 + w1) + w2 * h1;
    h3 = w0 * w0 * w0 + w1 * (w0 * w0 + w1 * (w0 + w1)) + w2 * h2;
    dh3 = {h2 + w0 * (h1 + w0), h2 + w1 * (h1 + w1), h2 + w2 * (h1 + w2)};
  }
};

// The divergence theorem turns ∫ f dV into ∮ F·n dA with ∂F_x/∂x = f; on a
// triangle n dA = (e1 × e2) ds dt, so only one component of the unnormalised
// normal d is needed per integral:
//   ∫1 = ∮ x n_x,  ∫x = ∮ x²/2 n_x,  ∫x² = ∮ x³/3 n_x,  ∫xy = ∮ x²y/2 n_x,
// and likewise for y, z with yz and zx. The reference point is subtracted
// from every corner first, so a body far from the origin loses no
// precision; `absolute_volume` sums the magnitudes of the triangles' volume
// terms, the scale against which the total's rounding is judged.
VolumeIntegrals integrate_mesh(const Mesh& mesh, const Eigen::Vector3d& reference, double& absolute_volume) {
  VolumeIntegrals sum;
  absolute_volume = 0;
  const auto positions = mesh.positions();
  for (const Mesh::Triangle& tri : mesh.triangles()) {
    const Eigen::Vector3d p0 = positions[tri[0]].cast<double>() - reference;
    const Eigen::Vector3d p1 = positions[tri[1]].cast<double>() - reference;
    const Eigen::Vector3d p2 = positions[tri[2]].cast<double>() - reference;
    const Eigen::Vector3d d = (p1 - p0).cross(p2 - p0);
    const CornerPolynomials x(p0.x(), p1.x(), p2.x());
    const CornerPolynomials y(p0.y(), p1.y(), p2.y());
    const CornerPolynomials z(p0.z(), p1.z(), p2.z());

    const double volume_term = d.x() * x.h1;
    sum.volume += volume_term;
    absolute_volume += std::abs(volume_term);
    sum.first += Eigen::Vector3d(d.x() * x.h2, d.y() * y.h2, d.z() * z.h2);
    sum.squares += Eigen::Vector3d(d.x() * x.h3, d.y() * y.h3, d.z() * z.h3);
    sum.products += Eigen::Vector3d(d.x() * (p0.y() * x.dh3[0] + p1.y() * x.dh3[1] + p2.y() * x.dh3[2]),
                                    d.y() * (p0.z() * y.dh3[0] + p1.z() * y.dh3[1] + p2.z() * y.dh3[2]),
                                    d.z() * (p0.x() * z.dh3[0] + p1.x() * z.dh3[1] + p2.x() * z.dh3[2]));
  }
  // The constant factors left out of the loop: the parameter-triangle
  // integrals above times 1, 1/2, 1/3 and 1/2 from the antiderivatives.
  sum.volume /= 6;
  sum.first /= 24;
  sum.squares /= 60;
  sum.products /= 120;
  absolute_volume /= 6;
  return sum;
}

// Unit-density properties (mass = volume) with inertia about the centre of
// mass; the principal axes are left for `finish`.
MassProperties unit_density_mesh(const Mesh& mesh) {
  if (mesh.report().open())
    throw UsageError("the mesh is open (" + std::to_string(mesh.report().boundary_edges) +
                     " boundary edges): it encloses no volume, so it has no mass properties");
  const Eigen::Vector3d reference = 0.5 * (mesh.bounds().min + mesh.bounds().max);
  double absolute_volume = 0;
  const VolumeIntegrals in = integrate_mesh(mesh, reference, absolute_volume);
  // A flat mesh's terms cancel to rounding noise rather than to exactly 0.
  if (!(in.volume > 1e-12 * absolute_volume)) {
    std::ostringstream s;
    s << "the mesh encloses a signed volume of " << in.volume
      << ", not > 0: its triangles face inward or it is flat, so it has no mass properties";
    throw UsageError(s.str());
  }

  const Eigen::Vector3d centre = in.first / in.volume;  // relative to the reference point
  // Inertia about the reference point: I = ∫ (r·r 1 - r rᵀ) dV.
  Eigen::Matrix3d about_reference;
  about_reference(0, 0) = in.squares.y() + in.squares.z();
  about_reference(1, 1) = in.squares.z() + in.squares.x();
  about_reference(2, 2) = in.squares.x() + in.squares.y();
  about_reference(0, 1) = about_reference(1, 0) = -in.products.x();
  about_reference(1, 2) = about_reference(2, 1) = -in.products.y();
  about_reference(2, 0) = about_reference(0, 2) = -in.products.z();
  // Parallel-axis theorem, back to the centre of mass.
  const Eigen::Matrix3d shift =
      in.volume * (centre.squaredNorm() * Eigen::Matrix3d::Identity() - centre * centre.transpose());

  MassProperties unit;
  unit.volume = unit.mass = in.volume;
  unit.centre_of_mass = reference + centre;
  unit.inertia = about_reference - shift;
  return unit;
}

MassProperties unit_density_sphere(const Sphere& sphere) {
  const double r = sphere.radius;
  MassProperties unit;
  unit.volume = unit.mass = 4.0 / 3.0 * std::numbers::pi * r * r * r;
  unit.inertia = Eigen::Matrix3d::Identity() * (0.4 * unit.mass * r * r);
  return unit;
}

MassProperties unit_density_box(const Box& box) {
  const Eigen::Vector3d h = box.half_extents;
  const Eigen::Vector3d squared = h.cwiseProduct(h);
  MassProperties unit;
  unit.volume = unit.mass = 8 * h.x() * h.y() * h.z();
  // Full side 2h: m (a² + b²) / 12 = m (h_a² + h_b²) / 3.
  unit.inertia = (unit.mass / 3 * Eigen::Vector3d(squared.y() + squared.z(), squared.z() + squared.x(),
                                                  squared.x() + squared.y()))
                     .asDiagonal();
  return unit;
}

MassProperties unit_density(const Shape& shape) {
  if (const Mesh* mesh = std::get_if<Mesh>(&shape.geometry())) return unit_density_mesh(*mesh);
  if (const Sphere* sphere = std::get_if<Sphere>(&shape.geometry())) return unit_density_sphere(*sphere);
  if (const Box* box = std::get_if<Box>(&shape.geometry())) return unit_density_box(*box);
  throw UsageError("a half-space has no finite mass; it can only be static");
}

// Scales unit-density properties by `density` and finds the principal axes.
MassProperties finish(MassProperties unit, double density) {
  MassProperties m = unit;
  m.mass = unit.volume * density;
  // Symmetric by construction up to rounding; the solver reads one triangle.
  m.inertia = 0.5 * density * (unit.inertia + unit.inertia.transpose());

  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver(m.inertia);
  m.principal_moments = solver.eigenvalues();  // ascending
  Eigen::Matrix3d axes = solver.eigenvectors();
  // An eigenvector's sign is arbitrary: fix it so its largest component
  // (the first of equals) is positive, so results do not depend on solver
  // internals, then make the basis right-handed.
  for (int k = 0; k < 3; ++k) {
    Eigen::Index largest = 0;
    axes.col(k).cwiseAbs().maxCoeff(&largest);
    if (axes(largest, k) < 0) axes.col(k) = -axes.col(k);
  }
  if (axes.determinant() < 0) axes.col(2) = -axes.col(2);
  m.principal_rotation = Eigen::Quaterniond(axes).normalized();
  return m;
}

void check_positive(double value, const char* what) {
  if (!std::isfinite(value) || !(value > 0)) {
    std::ostringstream s;
    s << what << " " << value << " must be finite and > 0";
    throw UsageError(s.str());
  }
}

}  // namespace

Pose MassProperties::principal_frame() const { return Pose{centre_of_mass, principal_rotation}; }

MassProperties mass_properties(const Shape& shape, double density) {
  check_positive(density, "density");
  return finish(unit_density(shape), density);
}

MassProperties mass_properties_for_mass(const Shape& shape, double mass) {
  check_positive(mass, "mass");
  const MassProperties unit = unit_density(shape);
  const double density = mass / unit.volume;
  if (!std::isfinite(density) || !(density > 0)) {
    std::ostringstream s;
    s << "mass " << mass << " over volume " << unit.volume << " gives density " << density
      << ", which is not finite and > 0";
    throw UsageError(s.str());
  }
  MassProperties m = finish(unit, density);
  m.mass = mass;
  return m;
}

}  // namespace rtcd::sim
