// The bounding-volume hierarchy the device traverses (kernel/bvh.h): built
// once per mesh on the host with binned SAH, then flattened depth first
// with escape links.
#pragma once

#include <vector>

#include "rtcd/kernel/bvh.h"
#include "rtcd/mesh.hpp"

namespace rtcd {

struct FlatBvh {
  std::vector<rtcd_bvh_node> nodes;  // depth first: a node, its first subtree, its second
  std::vector<rtcd_uint> primitives;  // triangle ids, each leaf a range
};

FlatBvh build_flat_bvh(const Mesh& mesh);

}  // namespace rtcd
