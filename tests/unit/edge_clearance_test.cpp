// A watched edge's clearance in walking steps (kernel/trace.h), on a
// brute-force tracer over a box: looked up in the first walking step, kept
// less the motion so far, and an edge tested again only once the pair has
// moved that far since its full step.
#include <gtest/gtest.h>

#include "rtcd/kernel/brute.h"
#include "rtcd/kernel/fold.h"
#include "rtcd/kernel/walk.h"
#include "rtcd/mesh_gen.hpp"

// The tracer trace.h calls: every triangle of one mesh (named apart from the
// CPU executor's rtcd_tracer, so the program holds one definition of each).
#define rtcd_tracer BruteTracer
struct BruteTracer {
  const rtcd::Mesh* mesh;
  const rtcd_vec3* positions() const { return reinterpret_cast<const rtcd_vec3*>(mesh->positions().data()); }
  const rtcd_uint* triangles() const { return reinterpret_cast<const rtcd_uint*>(mesh->triangles().data()); }
  rtcd_uint count() const { return rtcd_uint(mesh->triangle_count()); }
};
static rtcd_hit rtcd_tracer_first_hit(const rtcd_tracer* t, const rtcd_ray* ray, float t_max) {
  return rtcd_brute_first_hit(ray, t->positions(), t->triangles(), t->mesh->zero_area().data(), t->count(), t_max);
}
static rtcd_int rtcd_tracer_nearest(const rtcd_tracer* t, rtcd_vec3 point, float radius, float) {
  return rtcd_brute_nearest(point, radius, t->positions(), t->triangles(), t->mesh->zero_area().data(), t->count());
}
static rtcd_walk_result rtcd_tracer_walk(const rtcd_tracer* t, const rtcd_ray* ray, rtcd_int start, rtcd_uint steps) {
  return rtcd_walk(ray, t->positions(), t->triangles(), reinterpret_cast<const rtcd_int*>(t->mesh->neighbors().data()),
                   t->mesh->zero_area().data(), start, steps);
}
static int rtcd_tracer_leaves(const rtcd_tracer* t, rtcd_int triangle, rtcd_vec3 direction) {
  const Eigen::Vector3f& n = t->mesh->triangle_normals()[size_t(triangle)];
  return rtcd_dot(direction, rtcd_v3(n.x(), n.y(), n.z())) > 0.0f;
}
static int rtcd_tracer_fold_free(const rtcd_tracer*, rtcd_int, rtcd_vec3, rtcd_vec3, float) { return 1; }
static float rtcd_tracer_distance2(const rtcd_tracer* t, rtcd_int triangle, rtcd_vec3 point) {
  const rtcd_uint* tri = t->triangles() + 3 * triangle;
  return rtcd_point_triangle_distance2(point, t->positions()[tri[0]], t->positions()[tri[1]], t->positions()[tri[2]]);
}

#include "rtcd/kernel/trace.h"

namespace {

// A box of half size 1 (top face at z = 1) and an edge 0.2 long lying 0.5
// above its top face: the middle's distance less half the length is 0.4.
struct EdgeAboveABox : ::testing::Test {
  rtcd::Mesh box = rtcd::gen::box({1, 1, 1});
  rtcd_tracer tracer{&box};
  rtcd_trace_params params{};
  rtcd_candidate edge{};

  void SetUp() override {
    params.watch_lo = rtcd_v3(-2, -2, -2);
    params.watch_hi = rtcd_v3(2, 2, 2);
    params.extension = 1.0f;
    params.reach = 0.6f;
    params.max_walk_steps = 32;
    params.predictive = 1;
    params.watch = 1;
    params.iterative = 1;
    params.edges = 1;
    edge.vertex = 100;
    edge.start = -1;
    edge.entry = -1;  // as the full step leaves it
    edge.origin = rtcd_v3(-0.1f, 0, 1.5f);
    edge.direction = rtcd_v3(0.2f, 0, 0);
  }

  rtcd_outcome trace(float moved, rtcd_int entry) {
    params.moved = moved;
    edge.entry = entry;
    rtcd_outcome o;
    rtcd_outcome_init(&o, edge.vertex);
    rtcd_edge_trace(&tracer, &params, &edge, &o);
    return o;
  }
};

TEST_F(EdgeAboveABox, FirstWalkingStepKeepsTheClearanceLessTheMotionSoFar) {
  const rtcd_outcome o = trace(0.1f, -1);
  EXPECT_EQ(o.kind, RTCD_RAY_WATCHED);
  EXPECT_EQ(o.nearest_query, 1);
  EXPECT_EQ(o.edge_rays, 0) << "clear of the surface: no ray";
  EXPECT_NEAR(rtcd_bits_float(o.entry), 0.3f, 1e-6f) << "0.4 measured after a motion of 0.1";
}

TEST_F(EdgeAboveABox, LaterStepsTestTheEdgeOnlyOnceThePairHasMovedItsClearance) {
  const rtcd_int kept = rtcd_float_bits(0.3f);
  rtcd_outcome o = trace(0.25f, kept);
  EXPECT_EQ(o.kind, RTCD_RAY_WATCHED);
  EXPECT_EQ(o.edge_rays, 0);
  EXPECT_EQ(o.nearest_query, 0);
  EXPECT_EQ(o.entry, kept);
  o = trace(0.35f, kept);
  EXPECT_EQ(o.kind, RTCD_RAY_WATCHED);
  EXPECT_GE(o.edge_rays, 1) << "moved past its clearance: tested again";
  EXPECT_EQ(o.entry, kept);
}

TEST_F(EdgeAboveABox, APairThatMovedMoreThanHalfTheReachTestsByRaysWithoutALookup) {
  const rtcd_outcome o = trace(0.35f, -1);
  EXPECT_EQ(o.nearest_query, 0);
  EXPECT_GE(o.edge_rays, 1);
  EXPECT_EQ(o.kind, RTCD_RAY_WATCHED);
  EXPECT_EQ(rtcd_bits_float(o.entry), 0.0f) << "no clearance: tested every step until the next full step";
}

TEST_F(EdgeAboveABox, NoSurfaceWithinReachDropsTheEdge) {
  params.reach = 0.2f;  // the ball of 0.1 + 0.2 + 0.1 around the middle misses the box
  const rtcd_outcome o = trace(0.1f, -1);
  EXPECT_EQ(o.kind, RTCD_RAY_DROPPED);
  EXPECT_EQ(o.edge_rays, 0);
}

TEST_F(EdgeAboveABox, AnEdgeNearTheSurfaceIsTestedInItsFirstWalkingStep) {
  edge.origin = rtcd_v3(-0.1f, 0, 1.05f);  // 0.05 above the face: clearance 0
  const rtcd_outcome o = trace(0.01f, -1);
  EXPECT_EQ(o.kind, RTCD_RAY_WATCHED);
  EXPECT_GE(o.edge_rays, 1);
  EXPECT_EQ(rtcd_bits_float(o.entry), 0.0f);
}

}  // namespace
