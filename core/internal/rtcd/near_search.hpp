// The kernel's search for a full job's near leaves and its distance bound
// (kernel/near.h) over the host's shapes: one search for the CPU
// executors and the OpenCL host (its devices run the kernel's own).
#pragma once

#include <cstddef>
#include <span>
#include <type_traits>

#include "rtcd/distance_bound.hpp"
#include "rtcd/kernel/near.h"
#include "rtcd/shape.hpp"

namespace rtcd {

// A DistanceBound as the kernel reads it.
struct DistanceBoundKernel {
  static rtcd_distance_grid grid(const DistanceBound& bound);
  static std::span<const float> values(const DistanceBound& bound) { return bound.values_; }
};

// The kernel reads RaySources::Node in place.
static_assert(sizeof(RaySources::Node) == sizeof(rtcd_source_node) && std::is_standard_layout_v<RaySources::Node> &&
              offsetof(RaySources::Node, hi) == offsetof(rtcd_source_node, hi) &&
              offsetof(RaySources::Node, child) == offsetof(rtcd_source_node, child));

inline rtcd_source_tree kernel_tree(const RaySources& sources) {
  return {reinterpret_cast<const rtcd_source_node*>(sources.nodes.data()), sources.order.data(),
          rtcd_uint(sources.nodes.size()), sources.first_edge(), sources.sphere_radius > 0.0f};
}

// Calls visit_node(n) for each leaf sources.nodes[n] of the source's tree
// that the search of the job framed by `frame` reaches (rtcd_near_next):
// those whose box, placed in the target's frame as the box around it (in
// double, grown well past rounding), meets the job's candidate box. Their
// items are a superset of the candidates rtcd_place_item takes, found by
// whole boxes: most of a body's items lie far from the overlap and are
// turned away without being placed. A node of edges is turned away too
// when the target's distance bound at its centre, less half its box's
// diagonal, puts every edge in it beyond `reach` (edge_reach) of the
// surface: one lookup instead of a test per edge. Each leaf at most once,
// in no particular order.
template <class VisitNode>
void visit_near_leaves(const rtcd_frame& frame, const RaySources& sources, const DistanceBound& target, double reach,
                       const VisitNode& visit_node) {
  const rtcd_source_tree tree = kernel_tree(sources);
  const rtcd_distance_grid grid = DistanceBoundKernel::grid(target);
  const float* values = DistanceBoundKernel::values(target).data();
  rtcd_near_search search;
  rtcd_near_begin(&search, &frame, reach, &tree);
  for (rtcd_uint n = rtcd_near_next(&search, &tree, &grid, values); n != RTCD_NO_LEAF;
       n = rtcd_near_next(&search, &tree, &grid, values))
    visit_node(uint32_t(n));
}

// Calls visit(item) for each item of the leaves visit_near_leaves reaches
// (origins and edges): each at most once, in no particular order.
template <class Visit>
void visit_near_items(const rtcd_frame& frame, const RaySources& sources, const DistanceBound& target, double reach,
                      const Visit& visit) {
  visit_near_leaves(frame, sources, target, reach, [&](uint32_t n) {
    for (uint32_t v : sources.items_of(n)) visit(v);
  });
}

}  // namespace rtcd
