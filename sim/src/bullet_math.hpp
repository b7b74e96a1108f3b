// Conversions between Bullet's single-precision types and rtcd's, and the
// clock the stages are timed with; shared by the dispatcher and the host.
#pragma once

#include <chrono>

#include <LinearMath/btTransform.h>

#include "rtcd/clock.hpp"
#include "rtcd/geometry.hpp"

namespace rtcd::sim {

inline btVector3 bt(const Eigen::Vector3d& v) { return {btScalar(v.x()), btScalar(v.y()), btScalar(v.z())}; }
inline Eigen::Vector3d eigen(const btVector3& v) { return {v.x(), v.y(), v.z()}; }

inline btTransform bt(const Pose& p) {
  const Eigen::Quaterniond& q = p.orientation;
  return btTransform(btQuaternion(btScalar(q.x()), btScalar(q.y()), btScalar(q.z()), btScalar(q.w())), bt(p.position));
}

inline Pose pose_of(const btTransform& t) {
  const btQuaternion q = t.getRotation();
  Pose p;
  p.position = eigen(t.getOrigin());
  p.orientation = Eigen::Quaterniond(q.w(), q.x(), q.y(), q.z()).normalized();
  return p;
}

}  // namespace rtcd::sim
