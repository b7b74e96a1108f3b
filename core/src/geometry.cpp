// Poses, boxes, closest points, equation 2.1 and the names of enums.
#include <algorithm>
#include <cmath>
#include <sstream>

#include "rtcd/config.hpp"
#include "rtcd/criterion.hpp"
#include "rtcd/error.hpp"
#include "rtcd/geometry.hpp"
#include "rtcd/kernel/types.h"
#include "rtcd/results.hpp"

namespace rtcd {

Pose checked(const Pose& pose) {
  const Eigen::Vector4d q = pose.orientation.coeffs();
  if (!pose.position.allFinite() || !q.allFinite()) throw UsageError("pose has a non-finite component");
  const double norm = q.norm();
  if (std::abs(norm - 1.0) > 1e-3) {
    std::ostringstream s;
    s << "pose quaternion has length " << norm << ", expected 1 (within 1e-3)";
    throw UsageError(s.str());
  }
  Pose p = pose;
  p.orientation.normalize();
  return p;
}

Eigen::Vector3d closest_on_triangle(const Eigen::Vector3d& p, const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                                    const Eigen::Vector3d& c) {
  const Eigen::Vector3d ab = b - a, ac = c - a, ap = p - a;
  const double d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0 && d2 <= 0) return a;
  const Eigen::Vector3d bp = p - b;
  const double d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0 && d4 <= d3) return b;
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) return a + d1 / (d1 - d3) * ab;
  const Eigen::Vector3d cp = p - c;
  const double d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0 && d5 <= d6) return c;
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) return a + d2 / (d2 - d6) * ac;
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && d4 - d3 >= 0 && d5 - d6 >= 0) return b + (d4 - d3) / ((d4 - d3) + (d5 - d6)) * (c - b);
  const double denom = va + vb + vc;
  if (!(denom > 0)) return a;  // degenerate triangle
  return a + ab * (vb / denom) + ac * (vc / denom);
}

double segment_distance(const Eigen::Vector3d& p0, const Eigen::Vector3d& p1, const Eigen::Vector3d& q0,
                        const Eigen::Vector3d& q1) {
  const Eigen::Vector3d d1 = p1 - p0, d2 = q1 - q0, r = p0 - q0;
  const double a = d1.squaredNorm(), e = d2.squaredNorm(), f = d2.dot(r);
  double s = 0, t = 0;
  if (a <= 0 && e <= 0) return r.norm();
  if (a <= 0) {
    t = std::clamp(f / e, 0.0, 1.0);
  } else {
    const double c = d1.dot(r);
    if (e <= 0) {
      s = std::clamp(-c / a, 0.0, 1.0);
    } else {
      const double b = d1.dot(d2), denom = a * e - b * b;
      s = denom > 0 ? std::clamp((b * f - c * e) / denom, 0.0, 1.0) : 0.0;
      t = (b * s + f) / e;
      if (t < 0) {
        t = 0;
        s = std::clamp(-c / a, 0.0, 1.0);
      } else if (t > 1) {
        t = 1;
        s = std::clamp((b - c) / a, 0.0, 1.0);
      }
    }
  }
  return ((p0 + s * d1) - (q0 + t * d2)).norm();
}

Aabb Aabb::transformed(const Pose& pose) const {
  return transformed(pose.orientation.toRotationMatrix(), pose.position);
}

Aabb Aabb::transformed(const Eigen::Matrix3d& rotation, const Eigen::Vector3d& translation) const {
  const Eigen::Vector3d center = 0.5 * (min + max);
  const Eigen::Vector3d half = 0.5 * (max - min);
  const Eigen::Vector3d c = rotation * center + translation;
  const Eigen::Vector3d h = rotation.cwiseAbs() * half;
  return {c - h, c + h};
}

// Equation 2.1 by the kernel's functions, which the devices run too.
double rotation_angle(const Eigen::Quaterniond& q1, const Eigen::Quaterniond& q2) {
  const double a[4] = {q1.w(), q1.x(), q1.y(), q1.z()}, b[4] = {q2.w(), q2.x(), q2.y(), q2.z()};
  return rtcd_rotation_angle(a, b);
}

double max_displacement(const Pose& relative_at_full_step, const Pose& relative_now, double max_radius) {
  const rtcd_pose a = to_kernel(relative_at_full_step), b = to_kernel(relative_now);
  return rtcd_max_displacement(&a, &b, max_radius);
}

const char* to_string(PairMode mode) {
  return mode == PairMode::full ? "full" : mode == PairMode::iterative ? "iterative" : "certified";
}
const char* to_string(ContactKind kind) {
  return kind == ContactKind::vertex ? "vertex" : kind == ContactKind::edge ? "edge" : "sphere";
}

RayCounts& RayCounts::operator+=(const RayCounts& o) {
  for (const RayCounter& c : kRayCounters) this->*c.field += o.*c.field;
  for (int e = 0; e < kLineStatusCount; ++e) walk_endings[e] += o.walk_endings[e];
  return *this;
}

void StepStats::reset() {
  std::vector<DeviceWork> kept = std::move(devices);
  kept.clear();
  *this = {};
  devices = std::move(kept);
}

static_assert(kLineStatusCount == RTCD_LINE_STATUS_COUNT, "results.hpp mirrors the kernel's line statuses");

const char* line_status_name(int status) {
  static const char* names[RTCD_LINE_STATUS_COUNT] = {"hit",  "behind",     "front",   "boundary",
                                                      "miss", "step_limit", "parallel"};
  return status >= 0 && status < RTCD_LINE_STATUS_COUNT ? names[status] : "?";
}

const char* to_string(MeshErrorKind kind) {
  switch (kind) {
    case MeshErrorKind::empty: return "empty";
    case MeshErrorKind::non_finite_coordinate: return "non_finite_coordinate";
    case MeshErrorKind::index_out_of_range: return "index_out_of_range";
    case MeshErrorKind::repeated_vertex: return "repeated_vertex";
    case MeshErrorKind::zero_area_triangle: return "zero_area_triangle";
    case MeshErrorKind::non_manifold_edge: return "non_manifold_edge";
    case MeshErrorKind::inconsistent_winding: return "inconsistent_winding";
    case MeshErrorKind::out_of_range: return "out_of_range";
    case MeshErrorKind::inverted: return "inverted";
    case MeshErrorKind::file: return "file";
  }
  return "?";
}

}  // namespace rtcd
