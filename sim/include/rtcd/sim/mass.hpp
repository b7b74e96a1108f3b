// Rigid-body mass properties of a shape of uniform density: volume, mass,
// centre of mass and inertia tensor, with the principal axes a dynamics
// engine wants (it simulates a body in the frame where inertia is diagonal).
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "rtcd/geometry.hpp"
#include "rtcd/shape.hpp"

namespace rtcd::sim {

struct MassProperties {
  double volume = 0;
  double mass = 0;
  Eigen::Vector3d centre_of_mass = Eigen::Vector3d::Zero();  // in the shape's frame
  Eigen::Matrix3d inertia = Eigen::Matrix3d::Zero();         // about the centre of mass, shape-frame axes
  Eigen::Vector3d principal_moments = Eigen::Vector3d::Zero();  // ascending eigenvalues of `inertia`
  // Principal axes → shape frame: column k of its matrix is the axis of
  // principal_moments[k]. A proper rotation (det +1). Where moments repeat,
  // any orthonormal basis of their plane is as good; the one given is a
  // deterministic function of the input.
  Eigen::Quaterniond principal_rotation = Eigen::Quaterniond::Identity();

  // Pose of the principal frame in the shape frame: {centre_of_mass, principal_rotation}.
  Pose principal_frame() const;
};

// Mass properties at `density` (mass per unit volume; finite and > 0).
// A mesh is integrated over its triangles by the divergence theorem, in
// double precision; spheres and boxes use their closed forms.
// Throws UsageError naming what is wrong when the density is not finite and
// > 0, when a mesh is open (its integrals depend on where the origin is) or
// encloses no positive volume (inverted or flat), or for a shape with no
// finite volume.
MassProperties mass_properties(const Shape& shape, double density);

// The same for a body of the given total mass (finite and > 0): density is
// mass / volume, and the result's mass is exactly `mass`.
MassProperties mass_properties_for_mass(const Shape& shape, double mass);

}  // namespace rtcd::sim
