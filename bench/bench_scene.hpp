// The benchmarks' pair: two 902-triangle concave blobs resting in a shallow
// overlap, B at b_offset from A (both unrotated).
#pragma once

#include <memory>

#include "rtcd/backend.hpp"
#include "rtcd/mesh_gen.hpp"
#include "rtcd/narrow_phase.hpp"

namespace rtcd::bench {

struct RestingPair {
  std::shared_ptr<const Shape> a, b;
  Eigen::Vector3d b_offset;
};

inline const RestingPair& resting_pair() {
  static const RestingPair pair = [] {
    RestingPair p{std::make_shared<Shape>(gen::concave_blob(902, 1)), std::make_shared<Shape>(gen::concave_blob(902, 2)),
                  {1.5, 0.1, 0.05}};
    // Slide B toward A along x until the pair has 20 contacts.
    auto narrow = make_narrow_phase("embree");
    const ShapeId sa = narrow->add_shape(p.a), sb = narrow->add_shape(p.b);
    const BodyPair pair{narrow->add_body(sa, {}), narrow->add_body(sb, {})};
    for (double x = 3.0; x > 0.5; x -= 0.005) {
      Pose pose;
      pose.position = {x, 0.1, 0.05};
      narrow->set_pose(pair.b, pose);
      if (narrow->detect(std::span(&pair, 1)).contacts.size() >= 20) {
        p.b_offset.x() = x;
        break;
      }
    }
    return p;
  }();
  return pair;
}

}  // namespace rtcd::bench
