// Shapes on the devices: every registered shape's data concatenated into
// one set of arrays, as the kernels read them (device_types.h).
#pragma once

#include <vector>

#include "device_types.h"
#include "rtcd/limits.hpp"
#include "rtcd/shape.hpp"

namespace rtcd::opencl {

// The concatenated shape data every device holds.
struct ShapeData {
  std::vector<rtcd_device_shape> table;
  std::vector<rtcd_box> bounds;  // per shape, in double: the frames' candidate boxes
  std::vector<rtcd_shape_traits> traits;  // per shape: what its jobs' parameters read
  std::vector<rtcd_shape_scale> scales;   // per shape: what its pairs' limits read
  std::vector<rtcd_vec3> positions, normals, origins, directions;
  // The source trees' leaves, numbered a shape in node order: per item
  // its leaf; the leaves' items, each leaf's in increasing order, as one
  // list a shape (its place by first_source), and each leaf's range of that
  // list (begin, end; by first_leaf): a device lists a full job's items
  // from its few near leaves instead of testing every item.
  std::vector<rtcd_uint> source_leaves, leaf_items, leaf_ranges;
  // On the host: each shape's leaf count and, from its first_node on, each
  // source-tree node's leaf number (the search finds nodes).
  std::vector<rtcd_uint> leaf_counts, first_node, leaf_of_node;
  // Fold guards: ring_first rebased into the one ring list, with a
  // closing entry after the last mesh's triangles.
  std::vector<rtcd_fold_face> fold_faces;
  std::vector<rtcd_uint> ring_first{0};
  std::vector<rtcd_int> ring;
  std::vector<rtcd_uint> triangles, primitives;
  std::vector<rtcd_int> neighbors;
  std::vector<rtcd_uchar> zero_area;
  std::vector<rtcd_bvh_node> nodes;
  std::vector<rtcd_bvh_wide_node> wide;

  template <class T, class S>
  static void append(std::vector<T>& to, const S& from) {
    const auto* data = reinterpret_cast<const T*>(from.data());
    to.insert(to.end(), data, data + from.size() * sizeof(from[0]) / sizeof(T));
  }

  // Appends the shape's data (its BVH too when `bvh`) and its table entry.
  void add(const Shape& shape, const ShapeScale& scale, bool bvh);
};

}  // namespace rtcd::opencl
