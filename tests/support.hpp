// Helpers shared by the test suites.
#pragma once

#include <algorithm>
#include <cctype>
#include <cmath>
#include <memory>
#include <set>
#include <tuple>

#include <Eigen/Geometry>

#include "rtcd/backend.hpp"
#include "rtcd/mesh_gen.hpp"
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

// A cube of half 1 whose +x face is a fan around `centre` (in that face's
// plane): moving the centre onto an edge makes a zero-area triangle, near
// it a sliver.
inline Mesh cube_with_fan(const Eigen::Vector3f& centre, MeshOptions options) {
  const Mesh box = gen::box({1, 1, 1});
  std::vector<Eigen::Vector3f> p(box.positions().begin(), box.positions().end());
  std::vector<Mesh::Triangle> t;
  for (size_t i = 0; i < box.triangle_count(); ++i)
    if (box.triangle_normals()[i].x() < 0.5f) t.push_back(box.triangles()[i]);
  std::vector<uint32_t> face;  // +x corners, counter-clockwise seen from +x
  for (uint32_t v = 0; v < p.size(); ++v)
    if (p[v].x() > 0) face.push_back(v);
  std::sort(face.begin(), face.end(), [&](uint32_t a, uint32_t b) {
    return std::atan2(p[a].z(), p[a].y()) < std::atan2(p[b].z(), p[b].y());
  });
  const uint32_t c = uint32_t(p.size());
  p.push_back(centre);
  for (size_t k = 0; k < 4; ++k) t.push_back({c, face[k], face[(k + 1) % 4]});
  return Mesh(p, t, options);
}

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
