// The bounding-volume hierarchy the device traverses (kernel/bvh.h): built
// once per mesh on the host with binned SAH, flattened depth first with
// escape links, and collapsed to RTCD_BVH_WIDTH children a node.
#pragma once

#include <vector>

#include "rtcd/kernel/bvh.h"
#include "rtcd/mesh.hpp"

namespace rtcd {

struct FlatBvh {
  std::vector<rtcd_bvh_node> nodes;  // depth first: a node, its first subtree, its second
  std::vector<rtcd_bvh_primitive> primitives;  // each leaf a range; no zero-area triangle
  std::vector<rtcd_bvh_wide_node> wide;  // depth first from the root; empty when `nodes` is
};

FlatBvh build_flat_bvh(const Mesh& mesh);

}  // namespace rtcd
