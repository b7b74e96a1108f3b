#include "shape_data.hpp"

#include <algorithm>

#include "bvh.hpp"
#include "rtcd/cpu_executor.hpp"
#include "rtcd/error.hpp"
#include "rtcd/near_search.hpp"

namespace rtcd::opencl {

void ShapeData::add(const Shape& shape, const ShapeScale& scale, bool bvh) {
  rtcd_device_shape d{};
  d.first_vertex = rtcd_uint(positions.size());
  d.first_triangle = rtcd_uint(triangles.size() / 3);
  d.first_node = rtcd_uint(nodes.size());
  d.first_wide = rtcd_uint(wide.size());
  d.first_primitive = rtcd_uint(primitives.size());
  d.first_source = rtcd_uint(origins.size());
  const RaySources& rs = shape.sources();
  d.source_count = rs.item_count();
  // Items as rtcd_place_item reads them: origins, then edges.
  for (uint32_t i = 0; i < rs.item_count(); ++i) {
    const Eigen::Vector3f o = rs.item_origin(i), dir = rs.item_direction(i);
    origins.push_back(rtcd_v3(o.x(), o.y(), o.z()));
    directions.push_back(rtcd_v3(dir.x(), dir.y(), dir.z()));
  }
  if (rs.order.size() != rs.item_count()) throw Error("a shape's ray sources are not indexed (RaySources::index)");
  d.first_source_node = rtcd_uint(source_nodes.size());
  d.source_node_count = rtcd_uint(rs.nodes.size());
  const rtcd_source_tree tree = kernel_tree(rs);
  source_nodes.insert(source_nodes.end(), tree.nodes, tree.nodes + tree.node_count);
  source_order.insert(source_order.end(), rs.order.begin(), rs.order.end());
  leaf_items.insert(leaf_items.end(), rs.order.begin(), rs.order.end());
  for (const RaySources::Node& node : rs.nodes)
    if (node.child == 0)
      std::sort(leaf_items.begin() + d.first_source + node.begin, leaf_items.begin() + d.first_source + node.end);
  most_items = std::max(most_items, d.source_count);
  if (const Mesh* mesh = shape.mesh()) {
    d.kind = RTCD_TARGET_MESH;
    d.triangle_count = rtcd_uint(mesh->triangle_count());
    append(positions, mesh->positions());
    append(triangles, mesh->triangles());
    append(neighbors, mesh->neighbors());
    append(normals, mesh->triangle_normals());
    const Mesh::FoldGuard& guard = mesh->fold_guard();
    append(fold_faces, guard.faces);
    const rtcd_uint base = rtcd_uint(ring.size());
    ring_first.pop_back();
    for (uint32_t first : guard.ring_first) ring_first.push_back(base + first);
    append(ring, guard.ring);
    zero_area.insert(zero_area.end(), mesh->zero_area().begin(), mesh->zero_area().end());
    if (bvh) {
      const FlatBvh tree = build_flat_bvh(*mesh);
      d.node_count = rtcd_uint(tree.nodes.size());
      nodes.insert(nodes.end(), tree.nodes.begin(), tree.nodes.end());
      wide.insert(wide.end(), tree.wide.begin(), tree.wide.end());
      primitives.insert(primitives.end(), tree.primitives.begin(), tree.primitives.end());
    }
  } else if (const auto* sphere = std::get_if<Sphere>(&shape.geometry())) {
    d.kind = RTCD_TARGET_SPHERE;
    d.radius = float(sphere->radius);
  } else if (const auto* box = std::get_if<Box>(&shape.geometry())) {
    d.kind = RTCD_TARGET_BOX;
    const Eigen::Vector3f h = box->half_extents.cast<float>();
    d.half_extents = rtcd_v3(h.x(), h.y(), h.z());
  } else {
    d.kind = RTCD_TARGET_HALFSPACE;
  }
  const DistanceBound& bound = shape.distance_bound();
  d.first_value = rtcd_uint(grid_values.size());
  const std::span<const float> values = DistanceBoundKernel::values(bound);
  grid_values.insert(grid_values.end(), values.begin(), values.end());
  grids.push_back(DistanceBoundKernel::grid(bound));
  table.push_back(d);
  bounds.push_back(to_kernel(shape.bounds()));
  traits.push_back(shape_traits(shape));
  scales.push_back(to_kernel(scale));
}

}  // namespace rtcd::opencl
