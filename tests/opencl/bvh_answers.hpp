// The BVH traversal of kernel/bvh.h against the brute force, ray by ray
// and point by point, with the tree's shape. Included by test files that
// each fix RTCD_BVH_STACK before it: the functions are static, so each file
// checks its own stack depth.
#pragma once

#include <gtest/gtest.h>

#include <algorithm>
#include <random>
#include <vector>

#include "opencl/bvh.hpp"
#include "rtcd/mesh_gen.hpp"

namespace rtcd::test {
namespace {

// The most nodes on a path from the root: how deep the traversal's stack
// would grow with no limit.
inline size_t bvh_depth(const FlatBvh& bvh, rtcd_uint n = 0) {
  const rtcd_bvh_node& node = bvh.nodes[n];
  if (node.count != 0) return 1;
  return 1 + std::max(bvh_depth(bvh, n + 1), bvh_depth(bvh, bvh.nodes[n + 1].escape));
}

// Sets `deepest` to the deepest tree's depth: where it passes the
// RTCD_BVH_STACK of the calling file, the traversal's escape-link path ran.
inline void expect_bvh_answers_as_the_brute_force(size_t& deepest) {
  deepest = 0;
  std::mt19937 g(5);
  std::uniform_real_distribution<float> u(-1.2f, 1.2f);
  for (const Mesh& mesh : {gen::concave_blob(902, 3), gen::torus(1.0, 0.3, 24, 12), gen::icosphere(1.0, 3)}) {
    const FlatBvh bvh = build_flat_bvh(mesh);
    deepest = std::max(deepest, bvh_depth(bvh));
    std::vector<int> seen(mesh.triangle_count(), 0);
    for (rtcd_uint t : bvh.primitives) ++seen[t];
    EXPECT_EQ(std::count(seen.begin(), seen.end(), 1), long(mesh.triangle_count())) << "each triangle in one leaf";
    ASSERT_FALSE(bvh.nodes.empty());
    EXPECT_EQ(bvh.nodes[0].escape, bvh.nodes.size());
    const auto* positions = reinterpret_cast<const rtcd_vec3*>(mesh.positions().data());
    const auto* triangles = reinterpret_cast<const rtcd_uint*>(mesh.triangles().data());
    const rtcd_uchar* zero_area = mesh.zero_area().data();
    const auto n = rtcd_uint(mesh.triangle_count());
    size_t hits = 0, stopped_early = 0;
    for (int i = 0; i < 4000; ++i) {
      const rtcd_vec3 origin = rtcd_v3(u(g), u(g), u(g));
      Eigen::Vector3f d(u(g), u(g), u(g));
      if (i % 7 == 0) d = Eigen::Vector3f(0, 0, u(g));  // axis-parallel: slabs with zero components
      if (d.norm() == 0.0f) continue;
      d.normalize();
      const rtcd_ray ray = rtcd_make_ray(origin, rtcd_v3(d.x(), d.y(), d.z()));
      const float t_max = i % 2 ? 3.0e38f : 0.2f;
      const rtcd_hit a = rtcd_bvh_first_hit(&ray, bvh.nodes.data(), rtcd_uint(bvh.nodes.size()), bvh.primitives.data(),
                                            positions, triangles, zero_area, t_max);
      const rtcd_hit b = rtcd_brute_first_hit(&ray, positions, triangles, zero_area, n, t_max);
      ASSERT_EQ(a.triangle, b.triangle) << "ray " << i;
      ASSERT_EQ(a.t, b.t) << "ray " << i;
      hits += b.triangle >= 0;
      const float radius = i % 3 ? 0.05f : 1.0f;
      const rtcd_int nearest = rtcd_brute_nearest(origin, radius, positions, triangles, zero_area, n);
      ASSERT_EQ(rtcd_bvh_nearest(origin, radius, 0.0f, bvh.nodes.data(), rtcd_uint(bvh.nodes.size()),
                                 bvh.primitives.data(), positions, triangles, zero_area),
                nearest)
          << "point " << i;
      // Stopping within `enough`: any triangle that near, else the nearest.
      const float enough = 0.5f * radius;
      const rtcd_int near_enough = rtcd_bvh_nearest(origin, radius, enough, bvh.nodes.data(),
                                                    rtcd_uint(bvh.nodes.size()), bvh.primitives.data(), positions,
                                                    triangles, zero_area);
      const auto distance2 = [&](rtcd_int t) {
        return rtcd_point_triangle_distance2(origin, positions[triangles[3 * t]], positions[triangles[3 * t + 1]],
                                             positions[triangles[3 * t + 2]]);
      };
      if (near_enough != nearest) {
        ASSERT_GE(near_enough, 0) << "point " << i;
        ASSERT_LE(distance2(near_enough), enough * enough) << "point " << i;
        ++stopped_early;
      }
    }
    EXPECT_GT(hits, 500u) << "too few hits: the comparison would be vacuous";
    EXPECT_GT(stopped_early, 0u) << "no query stopped within `enough`: that check would be vacuous";
  }
}

}  // namespace
}  // namespace rtcd::test
