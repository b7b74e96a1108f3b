// The shared kernel's ray/triangle location: facing, edge choice, watertightness.
#include <random>

#include <gtest/gtest.h>

#include "rtcd/kernel/locate.h"
#include "rtcd/kernel/tracer.h"
#include "rtcd/kernel/volumes.h"
#include "rtcd/mesh_gen.hpp"

namespace {

rtcd_vec3 k(const Eigen::Vector3f& v) { return rtcd_v3(v.x(), v.y(), v.z()); }
Eigen::Vector3f random_unit(std::mt19937& g) {
  std::normal_distribution<float> n;
  return Eigen::Vector3f(n(g), n(g), n(g)).normalized();
}

TEST(Locate, FacingIsTheSignOfDirectionDotNormalForEveryDominantAxis) {
  std::mt19937 g(7);
  std::uniform_real_distribution<float> u(-1, 1);
  int checked = 0;
  for (int i = 0; i < 2000; ++i) {
    const Eigen::Vector3f a(u(g), u(g), u(g)), b(u(g), u(g), u(g)), c(u(g), u(g), u(g));
    const Eigen::Vector3f d = random_unit(g);
    const float dn = d.dot((b - a).cross(c - a));
    if (std::abs(dn) < 1e-3f) continue;
    const rtcd_ray ray = rtcd_make_ray(rtcd_v3(0, 0, 0), k(d));
    const rtcd_location loc = rtcd_locate(&ray, k(a), k(b), k(c));
    EXPECT_EQ(loc.facing, dn > 0 ? 1 : -1) << "i=" << i;
    ++checked;
  }
  EXPECT_GT(checked, 1500);
}

TEST(Locate, DistanceAndInsideMatchAHandComputedCase) {
  // Triangle in the plane z = 2, normal +z; the ray leaves through it.
  const rtcd_ray ray = rtcd_make_ray(rtcd_v3(0.2f, 0.2f, 0), rtcd_v3(0, 0, 1));
  const rtcd_location loc = rtcd_locate(&ray, rtcd_v3(0, 0, 2), rtcd_v3(1, 0, 2), rtcd_v3(0, 1, 2));
  ASSERT_TRUE(loc.inside);
  EXPECT_EQ(loc.facing, 1);
  EXPECT_FLOAT_EQ(loc.t_num / loc.det, 2.0f);
}

TEST(Locate, EdgeChoiceFollowsAlgorithm2) {
  // v0 = (0,0), v1 = (1,0), v2 = (0,1) in z = 1; points beyond each edge.
  const rtcd_vec3 v0 = rtcd_v3(0, 0, 1), v1 = rtcd_v3(1, 0, 1), v2 = rtcd_v3(0, 1, 1);
  auto edge_for = [&](float x, float y) {
    const rtcd_ray ray = rtcd_make_ray(rtcd_v3(x, y, 0), rtcd_v3(0, 0, 1));
    return rtcd_locate(&ray, v0, v1, v2).edge;
  };
  EXPECT_EQ(edge_for(0.3f, -0.2f), 1);  // v < 0: beyond (v0, v1)
  EXPECT_EQ(edge_for(-0.2f, 0.3f), 0);  // u < 0: beyond (v2, v0)
  EXPECT_EQ(edge_for(0.8f, 0.8f), 2);   // u + v > 1: beyond (v1, v2)
  EXPECT_EQ(edge_for(-0.5f, -0.5f), 0); // both u and v < 0: Algorithm 2 tests u first
  EXPECT_EQ(edge_for(0.2f, 0.2f), -1);  // inside
}

// Rays aimed exactly at points of a shared edge, or at a shared vertex, of a
// closed mesh: some triangle always takes the ray (no gap).
TEST(Locate, NoGapAtSharedEdgesAndVertices) {
  const rtcd::Mesh mesh = rtcd::gen::icosphere(1.0, 2);
  std::mt19937 g(11);
  std::uniform_real_distribution<float> u(0, 1);
  int gaps = 0, rays = 0;
  for (size_t t = 0; t < mesh.triangle_count(); ++t) {
    for (int e = 0; e < 3; ++e) {
      const int32_t n = mesh.neighbors()[t][e];
      const auto& tri = mesh.triangles()[t];
      const Eigen::Vector3f a = mesh.positions()[tri[(e + 2) % 3]], b = mesh.positions()[tri[e]];
      for (int s = 0; s < 4; ++s) {
        const float w = s == 0 ? 0.0f : u(g);  // w = 0: through the shared vertex
        const Eigen::Vector3f target = a + w * (b - a);
        // A direction that crosses the surface there (not grazing a silhouette).
        const Eigen::Vector3f d = (target.normalized() + 0.6f * random_unit(g)).normalized();
        const Eigen::Vector3f origin = target - 0.5f * d;
        const rtcd_ray ray = rtcd_make_ray(k(origin), k(d));
        // The two triangles of the edge, and for a vertex its whole fan.
        std::vector<size_t> around;
        for (size_t f = 0; f < mesh.triangle_count(); ++f) {
          const auto& ft = mesh.triangles()[f];
          const uint32_t v = tri[(e + 2) % 3];
          if (w == 0.0f ? (ft[0] == v || ft[1] == v || ft[2] == v) : (int32_t(f) == n || f == t)) around.push_back(f);
        }
        bool transversal = true, taken = false;
        for (size_t f : around) transversal &= mesh.triangle_normals()[f].dot(d) > 0.05f;
        if (!transversal) continue;
        for (size_t f : around) {
          const auto& ft = mesh.triangles()[f];
          taken |= rtcd_locate(&ray, k(mesh.positions()[ft[0]]), k(mesh.positions()[ft[1]]), k(mesh.positions()[ft[2]]))
                       .inside != 0;
        }
        ++rays;
        if (!taken) ++gaps;
      }
    }
  }
  EXPECT_EQ(gaps, 0) << "of " << rays << " rays";
  EXPECT_GT(rays, 2000);
}

TEST(Volumes, SphereAndBoxStatuses) {
  const rtcd_vec3 x = rtcd_v3(1, 0, 0);
  rtcd_volume_hit h = rtcd_sphere_line(rtcd_v3(0.5f, 0, 0), x, 1.0f);
  EXPECT_EQ(h.status, RTCD_LINE_HIT);
  EXPECT_FLOAT_EQ(h.t, 0.5f);
  h = rtcd_sphere_line(rtcd_v3(-3, 0, 0), x, 1.0f);
  EXPECT_EQ(h.status, RTCD_LINE_FRONT);
  h = rtcd_sphere_line(rtcd_v3(1.5f, 0, 0), x, 1.0f);
  EXPECT_EQ(h.status, RTCD_LINE_BEHIND);
  EXPECT_FLOAT_EQ(h.t, -0.5f);
  EXPECT_EQ(rtcd_sphere_line(rtcd_v3(0, 2, 0), x, 1.0f).status, RTCD_LINE_MISS);
  h = rtcd_box_line(rtcd_v3(0.2f, 0.1f, 0), rtcd_v3(0, -1, 0), rtcd_v3(0.5f, 0.5f, 0.5f));
  EXPECT_EQ(h.status, RTCD_LINE_HIT);
  EXPECT_EQ(h.face, 3);  // -y
  EXPECT_FLOAT_EQ(h.t, 0.6f);
  EXPECT_EQ(rtcd_box_line(rtcd_v3(0, 0.7f, 0), x, rtcd_v3(0.5f, 0.5f, 0.5f)).status, RTCD_LINE_MISS);
}

}  // namespace

namespace {

// The unit box as a candidate box, the identity as the transform.
rtcd_frame unit_frame() {
  rtcd_frame f;
  for (int k = 0; k < 9; ++k) f.rotation[k] = k % 4 == 0 ? 1.0 : 0.0;
  for (int k = 0; k < 3; ++k) {
    f.translation[k] = 0.0;
    f.lo[k] = -1.0;
    f.hi[k] = 1.0;
  }
  return f;
}

// An edge is a candidate when its segment meets the candidate box, even
// with both ends outside it; a zero-length edge never is.
TEST(Edges, PlacementTakesSegmentsThroughTheBoxAndNoZeroLengthEdge) {
  const rtcd_frame f = unit_frame();
  rtcd_vec3 o, d;
  EXPECT_EQ(rtcd_place_edge(&f, rtcd_v3(-3, 0, 0), rtcd_v3(6, 0, 0), &o, &d), 1) << "through, both ends outside";
  EXPECT_EQ(rtcd_place_edge(&f, rtcd_v3(-3, 2, 0), rtcd_v3(6, 0, 0), &o, &d), 0) << "beside the box";
  EXPECT_EQ(rtcd_place_edge(&f, rtcd_v3(-3, 0, 0), rtcd_v3(1.9f, 0, 0), &o, &d), 0) << "stops short of it";
  EXPECT_EQ(rtcd_place_edge(&f, rtcd_v3(-2, -2, 0), rtcd_v3(4, 4, 0), &o, &d), 1) << "diagonal through it";
  EXPECT_EQ(rtcd_place_edge(&f, rtcd_v3(-0.5f, 0.25f, 0), rtcd_v3(1, 0.5f, 0.25f), &o, &d), 1) << "wholly inside";
  EXPECT_EQ(rtcd_place_edge(&f, rtcd_v3(0.8f, 1.5f, 0), rtcd_v3(0.7f, -0.7f, 0), &o, &d), 0)
      << "past a corner: its ends' box meets the box, the segment does not";
  EXPECT_EQ(rtcd_place_edge(&f, rtcd_v3(0.4f, 1.5f, 0), rtcd_v3(0.7f, -0.7f, 0), &o, &d), 1) << "across a corner";
  EXPECT_EQ(rtcd_place_edge(&f, rtcd_v3(0.5f, 0.5f, 0.5f), rtcd_v3(0, 0, 0), &o, &d), 0) << "zero length";
  rtcd_trace_params p{};
  p.first_edge = 4;
  p.edges = 0;
  EXPECT_EQ(rtcd_place_item(&f, &p, 5, rtcd_v3(-3, 0, 0), rtcd_v3(6, 0, 0), &o, &d), 0) << "edges switched off";
  p.edges = 1;
  EXPECT_EQ(rtcd_place_item(&f, &p, 5, rtcd_v3(-3, 0, 0), rtcd_v3(6, 0, 0), &o, &d), 1);
}

// The exact span of a line inside a sphere or a box, for an edge of any length.
TEST(Edges, VolumeSpansAreExact) {
  float a = 0, b = 0;
  ASSERT_TRUE(rtcd_volume_span(RTCD_TARGET_SPHERE, 1.0f, rtcd_v3(0, 0, 0), rtcd_v3(-2, 0, 0), rtcd_v3(4, 0, 0), &a, &b));
  EXPECT_FLOAT_EQ(a, 0.25f);
  EXPECT_FLOAT_EQ(b, 0.75f);
  ASSERT_TRUE(rtcd_volume_span(RTCD_TARGET_BOX, 0.0f, rtcd_v3(1, 0.5f, 0.5f), rtcd_v3(0, -1, 0), rtcd_v3(0, 4, 0), &a, &b));
  EXPECT_FLOAT_EQ(a, 0.125f);
  EXPECT_FLOAT_EQ(b, 0.375f);
  EXPECT_FALSE(rtcd_volume_span(RTCD_TARGET_BOX, 0.0f, rtcd_v3(1, 0.5f, 0.5f), rtcd_v3(0, -1, 0.5f), rtcd_v3(0, 4, 0), &a, &b))
      << "along a face: touching, not crossing";
  EXPECT_EQ(rtcd_box_nearest_face(rtcd_v3(0.9f, 0, 0), rtcd_v3(1, 1, 1)), 0);
  EXPECT_EQ(rtcd_box_nearest_face(rtcd_v3(0, 0, -0.95f), rtcd_v3(1, 1, 1)), 5);
}

}  // namespace
