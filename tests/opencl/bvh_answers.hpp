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
#include "support.hpp"

namespace rtcd::test {
namespace {

// The most entries the traversal's stack would hold with no limit: a wide
// node pushes all its children but the nearest before going on, so
// RTCD_BVH_WIDTH - 1 a level of the wide tree.
inline size_t bvh_stack_needed(const FlatBvh& bvh, rtcd_int w = 0) {
  size_t below = 0;
  for (rtcd_int c : bvh.wide[size_t(w)].child)
    if (c >= 0) below = std::max(below, bvh_stack_needed(bvh, c));
  return RTCD_BVH_WIDTH - 1 + below;
}

// The wide tree holds the binary tree's subtrees: each child's box is its
// binary subtree's, and its leaves are the binary leaves, each once.
inline void expect_wide_tree_of(const FlatBvh& bvh) {
  std::vector<std::pair<rtcd_uint, rtcd_uint>> binary_leaves, wide_leaves;
  for (const rtcd_bvh_node& n : bvh.nodes)
    if (n.count != 0) binary_leaves.emplace_back(n.first, n.count);
  for (const rtcd_bvh_wide_node& w : bvh.wide)
    for (int k = 0; k < RTCD_BVH_WIDTH; ++k) {
      if (w.child[k] == RTCD_BVH_NO_CHILD) continue;
      const rtcd_bvh_node& n = bvh.nodes[w.subtree[k]];
      EXPECT_EQ(w.lo_x[k], n.lo.x);
      EXPECT_EQ(w.hi_z[k], n.hi.z);
      if (w.child[k] <= -2) {
        EXPECT_EQ(w.child[k], RTCD_BVH_LEAF(n.first, n.count)) << "a leaf's code names its binary leaf";
        wide_leaves.emplace_back(n.first, n.count);
      } else {
        EXPECT_EQ(n.count, 0u) << "an inner child roots an inner binary subtree";
      }
    }
  std::sort(binary_leaves.begin(), binary_leaves.end());
  std::sort(wide_leaves.begin(), wide_leaves.end());
  EXPECT_EQ(wide_leaves, binary_leaves);
}

// Sets `stack_needed` to the deepest tree's bvh_stack_needed: where it
// passes the RTCD_BVH_STACK of the calling file, the escape-link path ran.
inline void expect_bvh_answers_as_the_brute_force(size_t& stack_needed) {
  stack_needed = 0;
  std::mt19937 g(5);
  std::uniform_real_distribution<float> u(-1.2f, 1.2f);
  MeshOptions keep;
  keep.allow_zero_area = true;
  const Mesh zero_area_cube = cube_with_fan({1, 0, -1}, keep);  // one triangle of zero area
  ASSERT_EQ(zero_area_cube.report().zero_area_triangles, 1u);
  for (const Mesh& mesh :
       {gen::concave_blob(902, 3), gen::torus(1.0, 0.3, 24, 12), gen::icosphere(1.0, 3), zero_area_cube}) {
    const FlatBvh bvh = build_flat_bvh(mesh);
    ASSERT_FALSE(bvh.wide.empty());
    stack_needed = std::max(stack_needed, bvh_stack_needed(bvh));
    expect_wide_tree_of(bvh);
    std::vector<int> seen(mesh.triangle_count(), 0);
    for (const rtcd_bvh_primitive& p : bvh.primitives) {
      ++seen[size_t(p.triangle)];
      for (size_t k = 0; k < 3; ++k) {
        const Eigen::Vector3f& v = mesh.positions()[mesh.triangles()[size_t(p.triangle)][k]];
        ASSERT_TRUE(p.corner[k].x == v.x() && p.corner[k].y == v.y() && p.corner[k].z == v.z())
            << "triangle " << p.triangle << "'s corner " << k << " in its leaf";
      }
    }
    for (size_t t = 0; t < seen.size(); ++t)  // no query answers a zero-area triangle: the tree leaves it out
      EXPECT_EQ(seen[t], mesh.zero_area()[t] ? 0 : 1) << "triangle " << t << " in leaves";
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
      const rtcd_hit a = rtcd_bvh_first_hit(&ray, bvh.nodes.data(), rtcd_uint(bvh.nodes.size()), bvh.wide.data(),
                                            bvh.primitives.data(), t_max);
      const rtcd_hit b = rtcd_brute_first_hit(&ray, positions, triangles, zero_area, n, t_max);
      ASSERT_EQ(a.triangle, b.triangle) << "ray " << i;
      ASSERT_EQ(a.t, b.t) << "ray " << i;
      hits += b.triangle >= 0;
      const float radius = i % 3 ? 0.05f : 1.0f;
      const rtcd_int nearest = rtcd_brute_nearest(origin, radius, positions, triangles, zero_area, n);
      ASSERT_EQ(rtcd_bvh_nearest(origin, radius, 0.0f, bvh.nodes.data(), rtcd_uint(bvh.nodes.size()), bvh.wide.data(),
                                 bvh.primitives.data()),
                nearest)
          << "point " << i;
      // Stopping within `enough`: any triangle that near, else the nearest.
      const float enough = 0.5f * radius;
      const rtcd_int near_enough =
          rtcd_bvh_nearest(origin, radius, enough, bvh.nodes.data(), rtcd_uint(bvh.nodes.size()), bvh.wide.data(),
                           bvh.primitives.data());
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
