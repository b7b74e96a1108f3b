// Helpers shared by the test suites.
#pragma once

#include <cctype>
#include <memory>
#include <set>
#include <tuple>

#include <Eigen/Geometry>

#include "rtcd/backend.hpp"
#include "rtcd/narrow_phase.hpp"

namespace rtcd::test {

inline Pose at(double x, double y, double z) {
  Pose p;
  p.position = {x, y, z};
  return p;
}

inline Pose at(const Eigen::Vector3d& position, const Eigen::Quaterniond& orientation) {
  Pose p;
  p.position = position;
  p.orientation = orientation.normalized();
  return p;
}

inline std::shared_ptr<const Shape> shape(Mesh mesh) { return std::make_shared<Shape>(std::move(mesh)); }

// A narrow phase holding two bodies, A and B, stepped pose by pose.
struct PairRig {
  std::unique_ptr<NarrowPhase> narrow;
  BodyId a = 0, b = 0;

  PairRig(const std::string& backend, std::shared_ptr<const Shape> shape_a, std::shared_ptr<const Shape> shape_b,
          const Config& config = {})
      : narrow(make_narrow_phase(backend, config)) {
    const ShapeId sa = narrow->add_shape(std::move(shape_a));
    const ShapeId sb = narrow->add_shape(std::move(shape_b));
    a = narrow->add_body(sa, Pose{});
    b = narrow->add_body(sb, Pose{});
  }

  StepResult step(const Pose& pose_a, const Pose& pose_b) {
    narrow->set_pose(a, pose_a);
    narrow->set_pose(b, pose_b);
    const BodyPair pair{a, b};
    return narrow->detect(std::span(&pair, 1));
  }
};

// (source, vertex) of every penetrating ray.
inline std::set<std::pair<int, uint32_t>> penetrating(const StepResult& r) {
  std::set<std::pair<int, uint32_t>> s;
  for (const Contact& c : r.contacts) s.insert({int(c.source), c.vertex});
  return s;
}

inline std::vector<std::string> usable_backends() {
  std::vector<std::string> names;
  for (const auto& b : available_backends())
    if (b.usable) names.push_back(b.name);
  return names;
}

// The usable backends but basic: those a test compares with basic.
inline std::vector<std::string> backends_beside_basic() {
  std::vector<std::string> names = usable_backends();
  std::erase(names, "basic");
  return names;
}

// A backend name as a test name: gtest takes letters, digits and '_' only.
inline std::string test_name(std::string backend) {
  for (char& c : backend)
    if (!std::isalnum(static_cast<unsigned char>(c))) c = '_';
  return backend;
}

}  // namespace rtcd::test
