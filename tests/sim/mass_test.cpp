// Mass properties: mesh volume integrals against closed forms, their
// behaviour under rigid motion, principal axes, and refused input.
#include <cmath>
#include <limits>
#include <numbers>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include "rtcd/error.hpp"
#include "rtcd/mesh_gen.hpp"
#include "rtcd/shape.hpp"
#include "rtcd/sim/mass.hpp"

namespace {

using rtcd::sim::MassProperties;
using rtcd::sim::mass_properties;
using rtcd::sim::mass_properties_for_mass;

constexpr double pi = std::numbers::pi;

void expect_relative(double actual, double expected, double tolerance, const std::string& what = {}) {
  EXPECT_NEAR(actual, expected, tolerance * std::abs(expected)) << what;
}

// Matrices and vectors compared relative to the expected one's size, so
// zero entries are held to the same absolute scale as the others.
template <typename A, typename B>
void expect_close(const A& actual, const B& expected, double tolerance, const std::string& what = {}) {
  EXPECT_LE((actual - expected).norm(), tolerance * expected.norm())
      << what << "\nactual:\n" << actual << "\nexpected:\n" << expected;
}

// Principal axes are a proper rotation that diagonalises the inertia into
// the ascending principal moments.
void expect_consistent_principal_frame(const MassProperties& m, const std::string& what = {}) {
  const Eigen::Matrix3d r = m.principal_rotation.toRotationMatrix();
  EXPECT_NEAR(r.determinant(), 1.0, 1e-12) << what;
  expect_close(r.transpose() * r, Eigen::Matrix3d::Identity(), 1e-12, what);
  EXPECT_LE(m.principal_moments[0], m.principal_moments[1]) << what;
  EXPECT_LE(m.principal_moments[1], m.principal_moments[2]) << what;
  expect_close(r * m.principal_moments.asDiagonal() * r.transpose(), m.inertia, 1e-12, what);
  const rtcd::Pose frame = m.principal_frame();
  EXPECT_EQ(frame.position, m.centre_of_mass) << what;
  EXPECT_EQ(frame.orientation.coeffs(), m.principal_rotation.coeffs()) << what;
}

// Inertia of a solid box of `density` about `point`, by the parallel-axis theorem.
Eigen::Matrix3d box_inertia_about(const Eigen::Vector3d& centre, const Eigen::Vector3d& half, double density,
                                  const Eigen::Vector3d& point) {
  const double mass = density * 8 * half.prod();
  const Eigen::Vector3d sq = half.cwiseProduct(half);
  const Eigen::Matrix3d own =
      (mass / 3 * Eigen::Vector3d(sq.y() + sq.z(), sq.z() + sq.x(), sq.x() + sq.y())).asDiagonal();
  const Eigen::Vector3d d = centre - point;
  return own + mass * (d.squaredNorm() * Eigen::Matrix3d::Identity() - d * d.transpose());
}

rtcd::Mesh moved(const rtcd::Mesh& mesh, const Eigen::Quaterniond& rotation, const Eigen::Vector3d& translation) {
  std::vector<Eigen::Vector3f> positions;
  for (const auto& p : mesh.positions()) positions.push_back((rotation * p.cast<double>() + translation).cast<float>());
  return rtcd::Mesh(positions, {mesh.triangles().begin(), mesh.triangles().end()});
}

std::vector<rtcd::Mesh::Triangle> reversed(std::span<const rtcd::Mesh::Triangle> triangles) {
  std::vector<rtcd::Mesh::Triangle> out;
  for (const auto& t : triangles) out.push_back({t[0], t[2], t[1]});
  return out;
}

TEST(Mass, SphereClosedForm) {
  const MassProperties m = mass_properties(rtcd::Shape(rtcd::Sphere{2.0}), 3.0);
  expect_relative(m.volume, 32 * pi / 3, 1e-15);
  expect_relative(m.mass, 32 * pi, 1e-15);
  EXPECT_EQ(m.centre_of_mass, Eigen::Vector3d::Zero());
  expect_close(m.inertia, Eigen::Matrix3d::Identity() * (0.4 * 32 * pi * 4), 1e-15);
  expect_close(m.principal_moments, Eigen::Vector3d::Constant(0.4 * 32 * pi * 4), 1e-15);
  expect_consistent_principal_frame(m);
}

TEST(Mass, BoxClosedForm) {
  const MassProperties m = mass_properties(rtcd::Shape(rtcd::Box{{1, 2, 3}}), 0.5);
  EXPECT_DOUBLE_EQ(m.volume, 48);
  EXPECT_DOUBLE_EQ(m.mass, 24);
  EXPECT_EQ(m.centre_of_mass, Eigen::Vector3d::Zero());
  // m (h_b² + h_c²) / 3 about each axis.
  expect_close(m.inertia, Eigen::Vector3d(104, 80, 40).asDiagonal().toDenseMatrix(), 1e-15);
  expect_close(m.principal_moments, Eigen::Vector3d(40, 80, 104), 1e-15);
  // The smallest moment is about the longest side, z.
  const Eigen::Matrix3d r = m.principal_rotation.toRotationMatrix();
  EXPECT_NEAR(std::abs(r.col(0).z()), 1.0, 1e-12);
  EXPECT_NEAR(std::abs(r.col(1).y()), 1.0, 1e-12);
  EXPECT_NEAR(std::abs(r.col(2).x()), 1.0, 1e-12);
  expect_consistent_principal_frame(m);
}

TEST(Mass, MeshBoxMatchesClosedForm) {
  const Eigen::Vector3d half(0.5, 1.0, 1.5);
  const MassProperties mesh = mass_properties(rtcd::Shape(rtcd::gen::box(half)), 2.5);
  const MassProperties exact = mass_properties(rtcd::Shape(rtcd::Box{half}), 2.5);
  expect_relative(mesh.volume, 6.0, 1e-9);
  expect_relative(mesh.mass, 15.0, 1e-9);
  EXPECT_LE(mesh.centre_of_mass.norm(), 1e-12);
  expect_close(mesh.inertia, exact.inertia, 1e-9);
  expect_relative(mesh.inertia(0, 0), 15.0 / 3 * (1.0 + 2.25), 1e-9);
  expect_close(mesh.principal_moments, exact.principal_moments, 1e-9);
  expect_consistent_principal_frame(mesh);
}

TEST(Mass, MovedMeshMovesCentreAndRotatesInertia) {
  const Eigen::Vector3d half(0.5, 1.0, 1.5);
  const rtcd::Mesh box = rtcd::gen::box(half);
  const Eigen::Quaterniond rotation(Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, -2, 0.5).normalized()));
  const Eigen::Vector3d translation(3, -2, 5);
  const MassProperties at_origin = mass_properties(rtcd::Shape(box), 2.5);
  const MassProperties m = mass_properties(rtcd::Shape(moved(box, rotation, translation)), 2.5);

  // The moved corners are rounded to single precision: about 1e-7 relative.
  const Eigen::Matrix3d r = rotation.toRotationMatrix();
  expect_relative(m.volume, at_origin.volume, 1e-6);
  expect_relative(m.mass, at_origin.mass, 1e-6);
  EXPECT_LE((m.centre_of_mass - translation).norm(), 1e-6);
  expect_close(m.inertia, r * at_origin.inertia * r.transpose(), 1e-6);
  expect_close(m.principal_moments, at_origin.principal_moments, 1e-6);
  expect_consistent_principal_frame(m);
  // Distinct moments: each principal axis is the rotated box axis, up to sign.
  const Eigen::Matrix3d in_box_frame = r.transpose() * m.principal_rotation.toRotationMatrix() *
                                       at_origin.principal_rotation.toRotationMatrix().transpose();
  expect_close(in_box_frame.cwiseAbs(), Eigen::Matrix3d::Identity(), 1e-6);
}

TEST(Mass, IcosphereApproachesTheSphere) {
  const double radius = 2.0, density = 3.0;
  const MassProperties exact = mass_properties(rtcd::Shape(rtcd::Sphere{radius}), density);
  double previous_error = 1;
  for (int level : {3, 4}) {
    const MassProperties m = mass_properties(rtcd::Shape(rtcd::gen::icosphere(radius, level)), density);
    const double error = std::abs(m.mass - exact.mass) / exact.mass;
    EXPECT_LT(error, previous_error) << "level " << level;  // refinement converges
    previous_error = error;
    if (level == 4) {
      expect_relative(m.volume, exact.volume, 0.01);
      expect_relative(m.mass, exact.mass, 0.01);
      EXPECT_LE(m.centre_of_mass.norm(), 1e-6 * radius);
      expect_close(m.inertia, exact.inertia, 0.01);
      expect_close(m.principal_moments, exact.principal_moments, 0.01);
      expect_consistent_principal_frame(m);
    }
  }
}

TEST(Mass, TorusMatchesClosedForm) {
  // Solid torus about its symmetry axis z: V = 2π² R r², I_zz = m (R² + 3r²/4),
  // I_xx = I_yy = m (R²/2 + 5r²/8). A 256 x 128 tessellation is inscribed in
  // it: the polygons' areas fall short by about (2π/n)²/6, under 1e-3.
  const double major = 2.0, minor = 0.5, density = 1.5;
  const MassProperties m = mass_properties(rtcd::Shape(rtcd::gen::torus(major, minor, 256, 128)), density);
  const double volume = 2 * pi * pi * major * minor * minor, mass = density * volume;
  const double axial = mass * (major * major + 0.75 * minor * minor);
  const double transverse = mass * (major * major / 2 + 0.625 * minor * minor);
  expect_relative(m.volume, volume, 2e-3);
  expect_relative(m.mass, mass, 2e-3);
  EXPECT_LE(m.centre_of_mass.norm(), 1e-6);
  expect_close(m.inertia, Eigen::Vector3d(transverse, transverse, axial).asDiagonal().toDenseMatrix(), 2e-3);
  expect_close(m.principal_moments, Eigen::Vector3d(transverse, transverse, axial), 2e-3);
  // The largest moment is about the symmetry axis.
  EXPECT_NEAR(std::abs(m.principal_rotation.toRotationMatrix().col(2).z()), 1.0, 1e-9);
  expect_consistent_principal_frame(m);
}

TEST(Mass, ConcaveUShapeFromFile) {
  // A 3 x 3 x 1 block less its opening [-0.5, 0.5] x [-0.5, 1.5]: two arms
  // and a bar, whose boxes give the exact answer.
  const rtcd::Mesh u = rtcd::Mesh::load(std::string(RTCD_DATA_DIR) + "/meshes/u_shape.obj");
  const double density = 2.0;
  const MassProperties m = mass_properties(rtcd::Shape(u), density);
  const Eigen::Vector3d centre(0, -1.0 / 7, 0);
  const Eigen::Matrix3d inertia = box_inertia_about({-1, 0, 0}, {0.5, 1.5, 0.5}, density, centre) +
                                  box_inertia_about({1, 0, 0}, {0.5, 1.5, 0.5}, density, centre) +
                                  box_inertia_about({0, -1, 0}, {0.5, 0.5, 0.5}, density, centre);
  expect_relative(m.volume, 7.0, 1e-12);
  expect_relative(m.mass, 14.0, 1e-12);
  EXPECT_LE((m.centre_of_mass - centre).norm(), 1e-12);
  expect_close(m.inertia, inertia, 1e-12);
  expect_consistent_principal_frame(m, "u_shape");
}

TEST(Mass, ConcaveBlobsHaveConsistentPrincipalFrames) {
  for (uint32_t seed : {1u, 7u, 42u}) {
    const rtcd::Mesh blob = rtcd::gen::concave_blob(902, seed, 1.3);
    const MassProperties m = mass_properties(rtcd::Shape(blob), 0.8);
    const std::string what = "seed " + std::to_string(seed);
    EXPECT_GT(m.volume, 0) << what;
    expect_relative(m.mass, 0.8 * m.volume, 1e-15, what);
    EXPECT_TRUE(blob.bounds().contains(m.centre_of_mass)) << what;
    // Any body's moments obey the triangle inequality.
    EXPECT_LE(m.principal_moments[2], m.principal_moments[0] + m.principal_moments[1]) << what;
    EXPECT_GT(m.principal_moments[0], 0) << what;
    expect_consistent_principal_frame(m, what);
  }
}

TEST(Mass, CavityIsSubtracted) {
  // An outward box with an inward-facing box inside: a hollow shell.
  const rtcd::Mesh outer = rtcd::gen::box({1, 1, 1}), inner = rtcd::gen::box({0.5, 0.5, 0.5});
  std::vector<Eigen::Vector3f> positions(outer.positions().begin(), outer.positions().end());
  std::vector<rtcd::Mesh::Triangle> triangles(outer.triangles().begin(), outer.triangles().end());
  const auto offset = uint32_t(positions.size());
  positions.insert(positions.end(), inner.positions().begin(), inner.positions().end());
  for (auto t : reversed(inner.triangles())) triangles.push_back({t[0] + offset, t[1] + offset, t[2] + offset});
  const MassProperties m = mass_properties(rtcd::Shape(rtcd::Mesh(positions, triangles)), 1.0);
  expect_relative(m.volume, 7.0, 1e-12);
  EXPECT_LE(m.centre_of_mass.norm(), 1e-12);
  // 8 (1 + 1) / 3 - 1 (0.25 + 0.25) / 3 about every axis.
  expect_close(m.inertia, Eigen::Matrix3d::Identity() * (16.0 / 3 - 1.0 / 6), 1e-12);
}

TEST(Mass, ForMassReturnsTheRequestedMass) {
  const rtcd::Shape torus(rtcd::gen::torus(2.0, 0.5, 48, 24));
  const rtcd::Shape sphere(rtcd::Sphere{0.3});
  const rtcd::Shape box(rtcd::Box{{0.1, 0.2, 0.3}});
  for (const rtcd::Shape* shape : {&torus, &sphere, &box}) {
    const MassProperties m = mass_properties_for_mass(*shape, 12.5);
    EXPECT_EQ(m.mass, 12.5);
    const MassProperties by_density = mass_properties(*shape, 12.5 / m.volume);
    EXPECT_DOUBLE_EQ(m.volume, by_density.volume);
    expect_close(m.inertia, by_density.inertia, 1e-14);
    expect_close(m.principal_moments, by_density.principal_moments, 1e-14);
    expect_consistent_principal_frame(m);
  }
}

TEST(Mass, RefusesNonPositiveOrNonFiniteDensityAndMass) {
  const rtcd::Shape box(rtcd::Box{{1, 1, 1}});
  const double nan = std::numeric_limits<double>::quiet_NaN(), inf = std::numeric_limits<double>::infinity();
  for (double bad : {0.0, -1.0, nan, inf, -inf}) {
    EXPECT_THROW(mass_properties(box, bad), rtcd::UsageError) << bad;
    EXPECT_THROW(mass_properties_for_mass(box, bad), rtcd::UsageError) << bad;
  }
  try {
    mass_properties(box, -2.0);
    FAIL();
  } catch (const rtcd::UsageError& e) {
    EXPECT_NE(std::string(e.what()).find("density"), std::string::npos) << e.what();
  }
}

TEST(Mass, RefusesMeshesThatEncloseNoVolume) {
  const rtcd::Mesh box = rtcd::gen::box({1, 1, 1});
  const std::vector<Eigen::Vector3f> positions(box.positions().begin(), box.positions().end());

  // A closed mesh turned inside out is already refused when it is built.
  EXPECT_THROW(rtcd::Mesh(positions, reversed(box.triangles())), rtcd::MeshError);

  // Open: without one face, outward or inverted, the integrals depend on the origin.
  std::vector<rtcd::Mesh::Triangle> open(box.triangles().begin(), box.triangles().end() - 2);
  for (const auto& triangles : {open, reversed(open)}) {
    const rtcd::Shape shape(rtcd::Mesh(positions, triangles));
    try {
      mass_properties(shape, 1.0);
      FAIL() << "open mesh accepted";
    } catch (const rtcd::UsageError& e) {
      EXPECT_NE(std::string(e.what()).find("open"), std::string::npos) << e.what();
    }
  }

  // Flat: a closed mesh of one triangle seen from both sides.
  const std::vector<Eigen::Vector3f> corners = {{0.1f, 0.2f, 0.3f}, {1.7f, 0.4f, -0.2f}, {0.3f, 1.9f, 0.6f}};
  const rtcd::Shape flat(rtcd::Mesh(corners, {{0, 1, 2}, {0, 2, 1}}));
  ASSERT_FALSE(std::get<rtcd::Mesh>(flat.geometry()).report().open());
  try {
    mass_properties(flat, 1.0);
    FAIL() << "flat mesh accepted";
  } catch (const rtcd::UsageError& e) {
    EXPECT_NE(std::string(e.what()).find("volume"), std::string::npos) << e.what();
  }
  EXPECT_THROW(mass_properties_for_mass(flat, 1.0), rtcd::UsageError);
}

}  // namespace
