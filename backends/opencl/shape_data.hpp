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
  // The source trees (kernel/near.h): their nodes (by first_source_node)
  // and items in tree order (RaySources::order, by first_source), which a
  // device searches for a full job's near leaves instead of testing every
  // item, and the same with each leaf's items in increasing order, which it
  // merges.
  std::vector<rtcd_source_node> source_nodes;
  std::vector<rtcd_uint> source_order, leaf_items;
  rtcd_uint most_items = 0;  // of any shape's source
  // Per shape, its distance bound, which the searches read; the grids'
  // values one after another (by first_value).
  std::vector<rtcd_distance_grid> grids;
  std::vector<float> grid_values;
  // Fold guards: ring_first rebased into the one ring list, with a
  // closing entry after the last mesh's triangles.
  std::vector<rtcd_fold_face> fold_faces;
  std::vector<rtcd_uint> ring_first{0};
  std::vector<rtcd_int> ring;
  std::vector<rtcd_uint> triangles;
  std::vector<rtcd_bvh_primitive> primitives;
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
