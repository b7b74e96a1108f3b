// Crossings without an inside vertex, on every usable backend: edges that
// cross the other body (planks laid crosswise), a sphere's cap in a box face
// or another sphere, and the edge cases of the edge test.
#include <cmath>
#include <set>
#include <tuple>

#include <gtest/gtest.h>

#include "rtcd/mesh_gen.hpp"
#include "same_steps.hpp"
#include "support.hpp"

namespace rtcd::test {
namespace {

class Edges : public ::testing::TestWithParam<std::string> {
 protected:
  PairRig rig(std::shared_ptr<const Shape> a, std::shared_ptr<const Shape> b, const Config& c = {}) {
    return PairRig(GetParam(), std::move(a), std::move(b), c);
  }
};

std::shared_ptr<const Shape> bar_mesh(double x, double y, double z) { return shape(gen::box({x, y, z})); }
std::shared_ptr<const Shape> bar_volume(double x, double y, double z) { return std::make_shared<Shape>(Box{{x, y, z}}); }

size_t count(const StepResult& r, ContactKind kind) {
  size_t n = 0;
  for (const Contact& c : r.contacts) n += c.kind == kind;
  return n;
}

// Two bars laid crosswise, B sunk 0.01 into A: no vertex of either is inside
// the other; the edges that cross push B up (or A down) by 0.01.
TEST_P(Edges, PlanksLaidCrosswise) {
  for (const Mode mode : {Mode::full, Mode::iterative, Mode::automatic}) {
    SCOPED_TRACE(to_string(mode));
    Config config;
    config.mode = mode;
    auto r = rig(bar_mesh(0.5, 0.05, 0.05), bar_mesh(0.05, 0.5, 0.05), config);
    // A first step 7.5 mm deep, then B sinks to 1 cm: judged on the second,
    // which walks in the walking modes.
    ASSERT_TRUE(r.step(Pose{}, at(0, 0, 0.0925)).pairs[0].colliding);
    const StepResult res = r.step(Pose{}, at(0, 0, 0.09));
    EXPECT_EQ(res.pairs[0].mode, mode == Mode::full ? PairMode::full : PairMode::iterative);
    ASSERT_TRUE(res.pairs[0].colliding);
    EXPECT_NEAR(res.pairs[0].max_depth, 0.01, 1e-6);
    EXPECT_EQ(count(res, ContactKind::vertex), 0u) << "no vertex is inside";
    EXPECT_EQ(res.stats.edge_contacts, res.contacts.size());
    size_t from_a = 0, from_b = 0;
    for (const Contact& c : res.contacts) {
      ASSERT_EQ(c.kind, ContactKind::edge);
      EXPECT_LT(c.edge[0], c.edge[1]);
      EXPECT_EQ(c.vertex, c.edge[0]);
      EXPECT_NEAR(c.depth, 0.01, 1e-6);
      // A's top edges lie at z = 0.05, B's bottom edges at z = 0.04.
      const double sign = c.source == Side::a ? -1.0 : 1.0;
      EXPECT_NEAR((c.push - Eigen::Vector3d(0, 0, sign * 0.01)).norm(), 0.0, 1e-6) << "edge " << c.edge[0] << "-" << c.edge[1];
      EXPECT_NEAR(c.origin.z(), c.source == Side::a ? 0.05 : 0.04, 1e-6);
      (c.source == Side::a ? from_a : from_b) += 1;
    }
    EXPECT_GE(from_a, 2u) << "A's two upper long edges";
    EXPECT_GE(from_b, 2u) << "B's two lower long edges";

    // The knob off: what no vertex ray sees is not seen.
    Config off = config;
    off.edge_contacts = false;
    auto blind = rig(bar_mesh(0.5, 0.05, 0.05), bar_mesh(0.05, 0.5, 0.05), off);
    const StepResult none = blind.step(Pose{}, at(0, 0, 0.09));
    EXPECT_FALSE(none.pairs[0].colliding);
    EXPECT_EQ(none.stats.edges_tested, 0u);
  }
}

// A bar's edges against a sphere are tested in closed form, every step:
// none casts a ray, and none is skipped.
TEST_P(Edges, ClosedFormTestsAreNeverSkipped) {
  Config config;
  config.mode = Mode::iterative;
  auto r = rig(bar_mesh(0.5, 0.05, 0.05), std::make_shared<Shape>(Sphere{0.3}), config);
  for (int step = 0; step < 3; ++step) {
    SCOPED_TRACE("step " + std::to_string(step));
    const StepResult res = r.step(Pose{}, at(0, 0, 0.33 - 0.001 * step));
    EXPECT_TRUE(res.pairs[0].colliding);
    EXPECT_GT(res.stats.edges_tested, 0u);
    EXPECT_EQ(res.stats.edge_rays, 0u);
    EXPECT_EQ(res.stats.edges_skipped, 0u);
  }
}

// A ring sinking into a bar as it turns and slides: the bar's top edges
// cross the ring's tube with no vertex inside. A walking step tests a
// watched edge only once the pair has moved its clearance, and finds each
// crossing in the step it begins, as tracing every step in full does (the
// same edges, step for step).
TEST_P(Edges, WalkingStepsFindEveryCrossingFullStepsFind) {
  Config walking;
  walking.mode = Mode::automatic;
  Config full;
  full.mode = Mode::full;
  auto bar = bar_mesh(0.5, 0.05, 0.05), ring = shape(gen::torus(0.3, 0.08, 24, 8));
  auto walked = rig(bar, ring, walking), traced = rig(bar, ring, full);
  size_t crossings = 0, skipped = 0, walks = 0;
  for (int step = 0; step < 30; ++step) {
    SCOPED_TRACE("step " + std::to_string(step));
    const Eigen::Quaterniond turn(Eigen::AngleAxisd(0.01 * step, Eigen::Vector3d::UnitZ()));
    const Pose pose = at(Eigen::Vector3d(0.003 * step, 0, 0.14 - 0.002 * step), turn);
    const StepResult w = walked.step(Pose{}, pose), f = traced.step(Pose{}, pose);
    std::set<std::tuple<int, uint32_t, uint32_t>> edges_w, edges_f;
    for (const Contact& c : w.contacts)
      if (c.kind == ContactKind::edge) edges_w.insert({int(c.source), c.edge[0], c.edge[1]});
    for (const Contact& c : f.contacts)
      if (c.kind == ContactKind::edge) edges_f.insert({int(c.source), c.edge[0], c.edge[1]});
    ASSERT_EQ(edges_w, edges_f);
    crossings += edges_f.size();
    skipped += w.stats.edges_skipped;
    walks += w.stats.rays_iterative > 0;
  }
  EXPECT_GT(crossings, 50u) << "too few crossings: the comparison would be vacuous";
  EXPECT_GT(skipped, 20u) << "no edge skipped: the clearance went untested";
  EXPECT_GT(walks, 10u) << "the pair should walk most steps";
}

// edges_beside_contacts off: while a pair's vertex rays report contacts, its
// walking steps rest its edges. B's end lies inside A (two vertex
// contacts), then B slides back until no vertex is inside and only edges
// cross: the first walking step after still rests them and sees nothing,
// the next walks them again and finds the crossings a full trace finds.
TEST_P(Edges, EdgesRestBesideVertexContacts) {
  Config on, off;
  on.mode = off.mode = Mode::iterative;
  off.edges_beside_contacts = false;
  auto a = bar_mesh(0.5, 0.05, 0.05), b = bar_mesh(0.05, 0.5, 0.05);
  auto resting = rig(a, b, off), testing = rig(a, b, on), traced = rig(a, b);
  // B's end corners at y = 0 and z = 0.04, inside A.
  auto end_inside = [](int step) { return at(0, 0.5 - 0.001 * step, 0.09); };
  for (int step = 0; step < 3; ++step) {
    SCOPED_TRACE("end inside, step " + std::to_string(step));
    const StepResult r = resting.step(Pose{}, end_inside(step)), t = testing.step(Pose{}, end_inside(step));
    ASSERT_EQ(count(r, ContactKind::vertex), 2u);
    EXPECT_EQ(count(r, ContactKind::vertex), count(t, ContactKind::vertex));
    if (step == 0) continue;  // the full step
    ASSERT_EQ(r.pairs[0].mode, PairMode::iterative);
    EXPECT_EQ(r.stats.edges_tested, 0u) << "edges rest beside vertex contacts";
    EXPECT_GT(t.stats.edges_tested, 0u) << "the knob on tests them";
  }
  // B's end at y = -0.1, outside A: only edges cross.
  const Pose crossing = at(0, 0.4, 0.09);
  const StepResult lag = resting.step(Pose{}, crossing), seen = testing.step(Pose{}, crossing);
  EXPECT_EQ(lag.pairs[0].mode, PairMode::iterative);
  EXPECT_FALSE(lag.pairs[0].colliding) << "the step after the last vertex contact still rests the edges";
  EXPECT_TRUE(seen.pairs[0].colliding);
  const StepResult back = resting.step(Pose{}, crossing), full = traced.step(Pose{}, crossing);
  EXPECT_EQ(back.pairs[0].mode, PairMode::iterative);
  EXPECT_GT(back.stats.edges_tested, 0u);
  ASSERT_TRUE(back.pairs[0].colliding);
  std::set<std::tuple<int, uint32_t, uint32_t>> walked, found;
  for (const Contact& c : back.contacts) walked.insert({int(c.source), c.edge[0], c.edge[1]});
  for (const Contact& c : full.contacts) found.insert({int(c.source), c.edge[0], c.edge[1]});
  EXPECT_EQ(count(full, ContactKind::vertex), 0u);
  EXPECT_EQ(walked, found);
}

// edge_retest_motion: while the pair has moved less than it since the
// edges' last test, the watched edges are held (no test) and the edges that
// crossed are tested again, so the contacts are a full trace's; past it,
// every edge is tested again.
TEST_P(Edges, WatchedEdgesHeldUntilThePairMoves) {
  Config held, full;
  held.mode = Mode::iterative;
  held.edge_retest_motion = 0.005;
  full.mode = Mode::full;
  auto a = bar_mesh(0.5, 0.05, 0.05), b = bar_mesh(0.05, 0.5, 0.05);
  auto walking = rig(a, b, held), traced = rig(a, b, full);
  auto edges_of = [](const StepResult& r) {
    std::set<std::tuple<int, uint32_t, uint32_t>> edges;
    for (const Contact& c : r.contacts) edges.insert({int(c.source), c.edge[0], c.edge[1]});
    return edges;
  };
  // B sinks 1 mm a step from 7.5 mm deep, then jumps 6 mm (past the motion).
  const double heights[] = {0.0925, 0.0915, 0.0905, 0.0845};
  for (int step = 0; step < 4; ++step) {
    SCOPED_TRACE("step " + std::to_string(step));
    const Pose pose = at(0.001 * step, 0, heights[step]);
    const StepResult w = walking.step(Pose{}, pose), f = traced.step(Pose{}, pose);
    ASSERT_TRUE(f.pairs[0].colliding);
    EXPECT_EQ(edges_of(w), edges_of(f));
    if (step == 0) continue;
    ASSERT_EQ(w.pairs[0].mode, PairMode::iterative);
    EXPECT_GT(w.stats.edges_tested, 0u) << "the crossing edges are tested again";
    if (step < 3) {
      EXPECT_GT(w.stats.edges_held, 0u) << "moved under 3 mm since the last test";
    } else {
      EXPECT_EQ(w.stats.edges_held, 0u) << "moved past 5 mm: every edge is tested";
    }
  }
}

// Two boxes through each other's whole cross-section: contacts are local.
// Each of B's four long edges is 0.01 inside A's top or bottom face and is
// pushed out through it, so they do not add up to the smallest separating
// translation (0.09 along z); a solver pushes each point out where it is.
TEST_P(Edges, DeepCrossingGivesLocalContacts) {
  for (auto a : {bar_volume(0.5, 0.05, 0.05), bar_mesh(0.5, 0.05, 0.05)}) {
    auto r = rig(a, bar_volume(0.05, 0.5, 0.04));
    const StepResult res = r.step(Pose{}, Pose{});
    ASSERT_TRUE(res.pairs[0].colliding);
    EXPECT_EQ(count(res, ContactKind::vertex), 0u);
    size_t up = 0, down = 0;
    for (const Contact& c : res.contacts) {
      if (c.source == Side::a) {
        // A mesh's side faces have diagonals through B's middle, 0.04 from
        // B's top and bottom.
        EXPECT_TRUE(a->mesh());
        EXPECT_NEAR(c.depth, 0.04, 1e-6);
        continue;
      }
      EXPECT_NEAR(c.depth, 0.01, 1e-6);
      EXPECT_NEAR(std::abs(c.push.z()), 0.01, 1e-6);
      up += c.push.z() > 0;
      down += c.push.z() < 0;
    }
    EXPECT_EQ(up, 2u);
    EXPECT_EQ(down, 2u);
  }
}

// A box edge through a sphere, with both corners outside: the edge's span
// inside the sphere is exact; the contact lies at its middle.
TEST_P(Edges, BoxEdgeThroughASphere) {
  for (auto bar : {bar_volume(2.0, 0.05, 0.05), bar_mesh(2.0, 0.05, 0.05)}) {
    auto r = rig(bar, std::make_shared<Shape>(Sphere{1.0}));
    // The bar spans z 0.85 to 0.95 and x -2 to 2: its middle is inside the
    // sphere, its corners outside (the sphere's own sample points that fall
    // in the bar are its vertex contacts).
    const StepResult res = r.step(at(0, 0, 0.9), Pose{});
    ASSERT_TRUE(res.pairs[0].colliding);
    double deepest = 0.0;
    for (const Contact& c : res.contacts) {
      if (c.kind != ContactKind::edge) continue;
      EXPECT_EQ(c.source, Side::a);
      EXPECT_NEAR((c.origin.normalized() - c.push.normalized()).norm(), 0.0, 1e-6) << "out along the radius";
      EXPECT_NEAR(c.depth, 1.0 - c.origin.norm(), 1e-9);
      deepest = std::max(deepest, c.depth);
    }
    // The lower long edges, their middles at (0, ±0.05, 0.85); a mesh's
    // bottom diagonal, its middle at (0, 0, 0.85).
    EXPECT_NEAR(deepest, bar->mesh() ? 0.15 : 1.0 - std::hypot(0.05, 0.85), 1e-6);
  }
}

// A sphere whose cap pushes into a big box face, or into another sphere,
// between its sample points: the closed-form test finds it.
TEST_P(Edges, SphereCapBetweenSamplePoints) {
  const auto ball = std::make_shared<Shape>(Sphere{1.0});
  // The icosphere's origins nearest the face (-y, at the sample (0, -1, 0)
  // exactly) are kept out: tilt the sphere so no origin points at the face.
  const Pose tilted = at(Eigen::Vector3d(0, 0, 0),
                         Eigen::Quaterniond(Eigen::AngleAxisd(0.3, Eigen::Vector3d(1, 0.4, 0.2).normalized())));
  Pose box_pose = at(0, -1.0 - 2.0 + 0.002, 0);
  auto r = rig(ball, std::make_shared<Shape>(Box{{5.0, 2.0, 5.0}}));
  StepResult res = r.step(tilted, box_pose);
  ASSERT_TRUE(res.pairs[0].colliding);
  ASSERT_EQ(count(res, ContactKind::sphere), 1u);
  for (const Contact& c : res.contacts)
    if (c.kind == ContactKind::sphere) {
      EXPECT_NEAR(c.depth, 0.002, 1e-9);
      EXPECT_NEAR((c.push - Eigen::Vector3d(0, 0.002, 0)).norm(), 0.0, 1e-9);
      EXPECT_NEAR((c.origin - Eigen::Vector3d(0, -1, 0)).norm(), 0.0, 1e-9);
    }

  auto two = rig(ball, std::make_shared<Shape>(Sphere{0.5}));
  res = two.step(tilted, at(1.499, 0, 0));
  ASSERT_TRUE(res.pairs[0].colliding);
  double from_a = 0, from_b = 0;
  for (const Contact& c : res.contacts)
    if (c.kind == ContactKind::sphere) (c.source == Side::a ? from_a : from_b) = c.depth;
  EXPECT_NEAR(from_a, 0.001, 1e-9);
  EXPECT_NEAR(from_b, 0.001, 1e-9);

  // Apart by 0.001: nothing.
  res = two.step(tilted, at(1.501, 0, 0));
  EXPECT_FALSE(res.pairs[0].colliding);
}

// Touching is not crossing: an edge lying in the other body's face. Sizes
// are exact in float, so the bodies touch exactly (with 0.05 the two
// rounded faces overlap by 1.5e-9, deeper than the tolerance of a 0.1 edge).
// (An edge along another edge always puts a vertex on the other body's
// edge, where vertex rays report a zero depth: not an edge matter.)
// edges_both_sides off: a pair of meshes tests the finer mesh's edges only.
// A square rod (longest edge 0.61) passes through a coarse plank (1.42)
// with neither's vertex inside the other and clear of the plank's edges:
// only the rod's edges cross, and they are found whichever body comes
// first, in every mode (a walking step too). Planks laid crosswise (longest
// edges 1.005 and 0.80) cross along both's edges: the finer's alone are
// tested, and find what they find with both sides tested.
TEST_P(Edges, TheFinerMeshsEdgesOnly) {
  auto rod = bar_mesh(0.02, 0.02, 0.3), plank = bar_mesh(0.5, 0.5, 0.02);
  for (const Mode mode : {Mode::full, Mode::iterative}) {
    SCOPED_TRACE(to_string(mode));
    Config both, one;
    both.mode = one.mode = mode;
    one.edges_both_sides = false;
    for (const bool plank_first : {true, false}) {
      SCOPED_TRACE(plank_first ? "plank is a" : "rod is a");
      auto tested = plank_first ? rig(plank, rod, one) : rig(rod, plank, one);
      auto all = plank_first ? rig(plank, rod, both) : rig(rod, plank, both);
      const Side rod_side = plank_first ? Side::b : Side::a;
      StepResult r, b;
      for (const double y : {0.0, 0.001}) {
        const Pose p = at(0.25, y, 0.0);
        r = plank_first ? tested.step(Pose{}, p) : tested.step(p, Pose{});
        b = plank_first ? all.step(Pose{}, p) : all.step(p, Pose{});
      }
      EXPECT_EQ(r.pairs[0].mode, mode == Mode::full ? PairMode::full : PairMode::iterative);
      ASSERT_TRUE(r.pairs[0].colliding);
      EXPECT_EQ(count(r, ContactKind::vertex), 0u) << "no vertex is inside";
      std::set<std::tuple<int, uint32_t, uint32_t>> found, with_both;
      for (const Contact& c : r.contacts) {
        EXPECT_EQ(c.source, rod_side) << "the plank's edges are not tested";
        found.insert({int(c.source), c.edge[0], c.edge[1]});
      }
      for (const Contact& c : b.contacts) with_both.insert({int(c.source), c.edge[0], c.edge[1]});
      EXPECT_EQ(found, with_both) << "the plank's edges cross nothing here";
    }
    auto tested = rig(bar_mesh(0.5, 0.05, 0.05), bar_mesh(0.05, 0.4, 0.05), one);
    auto all = rig(bar_mesh(0.5, 0.05, 0.05), bar_mesh(0.05, 0.4, 0.05), both);
    StepResult r, b;
    for (const double z : {0.0925, 0.09}) {
      r = tested.step(Pose{}, at(0, 0, z));
      b = all.step(Pose{}, at(0, 0, z));
    }
    ASSERT_TRUE(r.pairs[0].colliding);
    std::set<std::tuple<int, uint32_t, uint32_t>> found, of_b;
    size_t from_a = 0;
    for (const Contact& c : r.contacts) found.insert({int(c.source), c.edge[0], c.edge[1]});
    for (const Contact& c : b.contacts) {
      if (c.source == Side::b) of_b.insert({int(c.source), c.edge[0], c.edge[1]});
      from_a += c.source == Side::a;
    }
    EXPECT_GT(from_a, 0u) << "A's edges cross too: with both sides they are found";
    EXPECT_EQ(found, of_b);
    EXPECT_LT(r.stats.edges_tested, b.stats.edges_tested);
    EXPECT_NEAR(r.pairs[0].max_depth, 0.01, 1e-6);
  }
}

TEST_P(Edges, TouchingIsNotCrossing) {
  Config config;
  config.mode = Mode::full;
  // B's lower edges lie in A's top face.
  auto r = rig(bar_mesh(0.5, 0.0625, 0.0625), bar_mesh(0.0625, 0.5, 0.0625), config);
  EXPECT_FALSE(r.step(Pose{}, at(0, 0, 0.125)).pairs[0].colliding);
  // Apart by a hair: nothing, however close; sunk by a hair: edge contacts.
  EXPECT_FALSE(r.step(Pose{}, at(0, 0, 0.125 + 1e-6)).pairs[0].colliding);
  // Sunk by 1e-5, ten times the tolerance of a unit edge: edge contacts.
  const StepResult sunk = r.step(Pose{}, at(0, 0, 0.125 - 1e-5));
  ASSERT_TRUE(sunk.pairs[0].colliding);
  EXPECT_NEAR(sunk.pairs[0].max_depth, 1e-5, 1e-9);
}

// An edge through the other body's vertex or along its edge, once sunk: the
// crossing is found, deterministically, at the right depth.
TEST_P(Edges, EdgeThroughAVertexAndAlongAnEdge) {
  // B turned 45 degrees about x: its lower edge is a ridge, sunk 0.01 into
  // A's top face along y; the ridge passes over A's top edges at y = ±0.05.
  const double h = 0.05 * std::sqrt(2.0);
  const Pose ridge = at(Eigen::Vector3d(0, 0, 0.05 + h - 0.01),
                        Eigen::Quaterniond(Eigen::AngleAxisd(M_PI / 4, Eigen::Vector3d::UnitY())));
  Config config;
  config.mode = Mode::full;
  auto r = rig(bar_mesh(0.5, 0.05, 0.05), bar_mesh(0.05, 0.5, 0.05), config);
  const StepResult res = r.step(Pose{}, ridge);
  ASSERT_TRUE(res.pairs[0].colliding);
  EXPECT_NEAR(res.pairs[0].max_depth, 0.01, 1e-5);
  // The same ridge exactly over A's corner vertex (x = 0.5).
  const Pose corner = at(Eigen::Vector3d(0.5, 0, 0.05 + h - 0.01),
                         Eigen::Quaterniond(Eigen::AngleAxisd(M_PI / 4, Eigen::Vector3d::UnitY())));
  auto fresh = [&] { return rig(bar_mesh(0.5, 0.05, 0.05), bar_mesh(0.05, 0.5, 0.05), config); };
  auto r1 = fresh(), r2 = fresh();
  const StepResult at_corner = r1.step(Pose{}, corner);
  ASSERT_TRUE(at_corner.pairs[0].colliding);
  EXPECT_LE(at_corner.pairs[0].max_depth, 0.01 + 1e-5);
  expect_same_step(at_corner, r2.step(Pose{}, corner), "the same poses twice");
}

// Every backend reports the same edge contacts as `basic`, bit for bit
// where they share the tracer (opencl-basic), to rounding elsewhere.
// Every backend but basic itself.
class EdgesBesideBasic : public Edges {};

TEST_P(EdgesBesideBasic, AgreesWithBasic) {
  // A ring's tube sunk crosswise into a plank, tilted.
  const Pose b_pose = at(Eigen::Vector3d(0.1, 0.4, 0.09),
                         Eigen::Quaterniond(Eigen::AngleAxisd(0.3, Eigen::Vector3d(0.2, 1, 0.1).normalized())));
  auto ours = rig(bar_mesh(0.5, 0.2, 0.05), shape(gen::torus(0.4, 0.06, 24, 8)));
  auto basic = PairRig("basic", bar_mesh(0.5, 0.2, 0.05), shape(gen::torus(0.4, 0.06, 24, 8)));
  const StepResult x = ours.step(Pose{}, b_pose), y = basic.step(Pose{}, b_pose);
  ASSERT_GT(x.stats.edge_contacts, 0u);
  if (GetParam() == "opencl-basic") {
    expect_same_step(x, y, "opencl-basic against basic");
    return;
  }
  ASSERT_EQ(x.contacts.size(), y.contacts.size());
  for (size_t k = 0; k < x.contacts.size(); ++k) {
    const Contact &c = x.contacts[k], &d = y.contacts[k];
    EXPECT_EQ(c.kind, d.kind);
    EXPECT_EQ(c.source, d.source);
    EXPECT_EQ(c.vertex, d.vertex);
    EXPECT_EQ(c.edge, d.edge);
    EXPECT_EQ(c.triangle, d.triangle) << "edge " << c.edge[0] << "-" << c.edge[1];
    EXPECT_NEAR(c.depth, d.depth, 1e-5);
    EXPECT_NEAR((c.origin - d.origin).norm(), 0.0, 1e-5);
    EXPECT_NEAR((c.push - d.push).norm(), 0.0, 1e-5);
    EXPECT_NEAR((c.normal - d.normal).norm(), 0.0, 1e-5);
  }
}

INSTANTIATE_TEST_SUITE_P(Backends, Edges, ::testing::ValuesIn(usable_backends()),
                         [](const auto& info) { return test_name(info.param); });
INSTANTIATE_TEST_SUITE_P(Backends, EdgesBesideBasic, ::testing::ValuesIn(backends_beside_basic()),
                         [](const auto& info) { return test_name(info.param); });

}  // namespace
}  // namespace rtcd::test
