// One test body, run against every usable backend: hand-computed contacts,
// iterative against full, predictive rays, and agreement with `basic`.
#include <cmath>
#include <random>

#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include "rtcd/backend.hpp"
#include "rtcd/error.hpp"
#include "rtcd/mesh_gen.hpp"
#include "same_steps.hpp"
#include "support.hpp"

namespace rtcd::test {
namespace {

class Conformance : public ::testing::TestWithParam<std::string> {
 protected:
  PairRig rig(std::shared_ptr<const Shape> a, std::shared_ptr<const Shape> b, const Config& c = {}) {
    return PairRig(GetParam(), std::move(a), std::move(b), c);
  }
};

// The thesis' ray contacts (Config::nearest_surface off): depth along the
// inward normal to where the ray leaves. The hand-computed cases below were
// worked out for them; tests/conformance/penetration_test.cpp has the
// contacts measured to the nearest surface.
Config ray_contacts() {
  Config c;
  c.nearest_surface = false;
  return c;
}

// The limits the hand-computed cube cases were worked out for. With larger
// (derived) extensions B's corners become candidates too, and their rays pass
// exactly through A's corners: a tie each tracer breaks its own way
// (fuzz/README.md).
Config hand_computed() {
  Config c = ray_contacts();
  c.distance_extension = 0.1;
  c.displacement_threshold = 0.05;
  c.max_walk_steps = 32;
  return c;
}

std::shared_ptr<const Shape> box_mesh(double h) { return shape(gen::box({h, h, h})); }
std::shared_ptr<const Shape> box_volume(double h) { return std::make_shared<Shape>(Box{{h, h, h}}); }

// Cube A (half 0.5) at the origin, cube B (half 0.6) at (1, 0, 0): exactly
// A's four +x vertices penetrate, along -(1, ±1, ±1)/√3, to B's face x = 0.4.
// A box mesh B's face x = 0.4 has a diagonal edge, which crosses A with
// neither end inside: an edge contact 0.1 deep at its middle, out through
// A's face x = 0.5.
// `b_mesh`: B is a box mesh, whose diagonal must give that edge contact.
void expect_cube_contacts(const StepResult& r, bool b_mesh,
                          const Eigen::Vector3d& a_position = Eigen::Vector3d::Zero()) {
  size_t vertex_contacts = 0, edge_contacts = 0;
  for (const Contact& c : r.contacts) {
    if (c.kind == ContactKind::edge) {
      ++edge_contacts;
      EXPECT_EQ(c.source, Side::b);
      EXPECT_NEAR((c.origin - a_position - Eigen::Vector3d(0.4, 0, 0)).norm(), 0.0, 1e-6);
      EXPECT_NEAR(c.depth, 0.1, 1e-6);
      EXPECT_NEAR((c.push - Eigen::Vector3d(0.1, 0, 0)).norm(), 0.0, 1e-6);
      continue;
    }
    ASSERT_EQ(c.kind, ContactKind::vertex);
    ++vertex_contacts;
    EXPECT_EQ(c.source, Side::a);
    const Eigen::Vector3d local = c.origin - a_position;
    EXPECT_NEAR(local.x(), 0.5, 1e-7);
    EXPECT_NEAR(std::abs(local.y()), 0.5, 1e-7);
    const Eigen::Vector3d inward = -Eigen::Vector3d(1, local.y() > 0 ? 1 : -1, local.z() > 0 ? 1 : -1) / std::sqrt(3.0);
    EXPECT_NEAR((c.direction - inward).norm(), 0.0, 1e-6);
    EXPECT_NEAR(c.depth, 0.1 * std::sqrt(3.0), 1e-6);
    EXPECT_NEAR(c.projected_depth, 0.1, 1e-6);
    EXPECT_NEAR((c.normal - Eigen::Vector3d(-1, 0, 0)).norm(), 0.0, 1e-6);
    EXPECT_NEAR((c.push - Eigen::Vector3d(-0.1, 0, 0)).norm(), 0.0, 1e-6);
  }
  EXPECT_EQ(vertex_contacts, 4u);
  EXPECT_EQ(edge_contacts, b_mesh ? 1u : 0u) << "B's face diagonal";
  ASSERT_EQ(r.pairs.size(), 1u);
  EXPECT_TRUE(r.pairs[0].colliding);
  EXPECT_NEAR(r.pairs[0].max_depth, 0.1 * std::sqrt(3.0), 1e-6);
}

TEST_P(Conformance, CubesAsMeshes) {
  auto r = rig(box_mesh(0.5), box_mesh(0.6), hand_computed());
  expect_cube_contacts(r.step(Pose{}, at(1, 0, 0)), true);
}

TEST_P(Conformance, CubesAsBoxVolumes) {
  auto r = rig(box_volume(0.5), box_volume(0.6), ray_contacts());
  expect_cube_contacts(r.step(Pose{}, at(1, 0, 0)), false);
}

TEST_P(Conformance, CubesMixed) {
  auto r1 = rig(box_mesh(0.5), box_volume(0.6), hand_computed());
  expect_cube_contacts(r1.step(Pose{}, at(1, 0, 0)), false);
  auto r2 = rig(box_volume(0.5), box_mesh(0.6), hand_computed());
  expect_cube_contacts(r2.step(Pose{}, at(1, 0, 0)), true);
}

TEST_P(Conformance, CubesFarFromTheOrigin) {
  auto r = rig(box_mesh(0.5), box_mesh(0.6), hand_computed());
  expect_cube_contacts(r.step(at(148376, 1234, -223423), at(148377, 1234, -223423)), true, {148376, 1234, -223423});
}

// A sphere of radius 0.5 at the origin against a box (half 0.5) at (0.9, 0, 0):
// the sphere's source points with x > 0.4 are inside and leave through x = 0.4.
TEST_P(Conformance, SphereAgainstBox) {
  auto sphere = std::make_shared<Shape>(Sphere{0.5});
  for (auto box : {box_volume(0.5), box_mesh(0.5)}) {
    auto r = rig(sphere, box, ray_contacts());
    const StepResult res = r.step(Pose{}, at(0.9, 0, 0));
    size_t expected = 0;
    for (const auto& o : sphere->sources().origins) expected += o.x() > 0.4f;
    ASSERT_GT(expected, 0u);
    size_t from_sphere = 0, deepest = 0;
    for (const Contact& c : res.contacts) {
      if (c.source != Side::a) {
        // A box mesh's face x = 0.4 has a diagonal through the sphere: an
        // edge contact at its middle (0.4, 0, 0), 0.1 inside.
        EXPECT_EQ(c.kind, ContactKind::edge);
        EXPECT_NEAR((c.origin - Eigen::Vector3d(0.4, 0, 0)).norm(), 0.0, 1e-6);
        EXPECT_NEAR((c.push - Eigen::Vector3d(0.1, 0, 0)).norm(), 0.0, 1e-6);
        continue;
      }
      if (c.kind == ContactKind::sphere) {
        // The closed-form test: the sphere's point nearest the box, 0.1 deep.
        ++deepest;
        EXPECT_NEAR((c.origin - Eigen::Vector3d(0.5, 0, 0)).norm(), 0.0, 1e-6);
        EXPECT_NEAR(c.depth, 0.1, 1e-6);
        EXPECT_NEAR((c.push - Eigen::Vector3d(-0.1, 0, 0)).norm(), 0.0, 1e-6);
        continue;
      }
      ++from_sphere;
      const Eigen::Vector3d u = c.origin / 0.5;
      EXPECT_NEAR(c.depth, (c.origin.x() - 0.4) / u.x(), 1e-5);
      EXPECT_NEAR((c.normal - Eigen::Vector3d(-1, 0, 0)).norm(), 0.0, 1e-6);
    }
    EXPECT_EQ(from_sphere, expected);
    EXPECT_EQ(deepest, box->mesh() ? 0u : 1u) << "the closed form runs against volumes only";
    for (const Contact& c : res.contacts) {
      if (c.kind == ContactKind::vertex) {
        EXPECT_EQ(c.source, Side::a) << "box corners lie outside the sphere";
      }
    }
  }
}

// A box mesh against a sphere volume: exact intersection as target.
TEST_P(Conformance, BoxAgainstSphereVolume) {
  auto r = rig(box_mesh(0.5), std::make_shared<Shape>(Sphere{1.0}));
  const StepResult res = r.step(Pose{}, at(1.2, 0, 0));
  // Corners (0.5, ±0.5, ±0.5) are 0.866 from the sphere's centre: inside.
  size_t from_box = 0;
  for (const Contact& c : res.contacts) {
    if (c.source != Side::a) continue;
    ++from_box;
    const Eigen::Vector3d exit = c.origin + c.depth * c.direction;
    EXPECT_NEAR((exit - Eigen::Vector3d(1.2, 0, 0)).norm(), 1.0, 1e-5);
    EXPECT_NEAR((c.normal - (exit - Eigen::Vector3d(1.2, 0, 0))).norm(), 0.0, 1e-5);
  }
  EXPECT_EQ(from_box, 4u);
}

// A cube sunk 0.1 into the ground: its four lower corners leave the
// half-space upward through the plane (never through a far side, as from a
// box ground), and the ground casts nothing.
// The ray runs along the corner's diagonal, 0.1 * sqrt(3) to the plane;
// the nearest surface is 0.1 straight below. Both push up by 0.1 (the ray
// contact by its projected depth).
TEST_P(Conformance, CubeSunkIntoHalfSpace) {
  for (const bool nearest : {false, true}) {
    SCOPED_TRACE(nearest ? "nearest surface" : "ray contacts");
    Config config;
    config.nearest_surface = nearest;
    auto r = rig(box_mesh(0.5), std::make_shared<Shape>(HalfSpace{}), config);
    const StepResult res = r.step(at(3, -2, 0.4), at(0, 0, 0));
    ASSERT_EQ(res.contacts.size(), 4u);
    for (const Contact& c : res.contacts) {
      EXPECT_EQ(c.source, Side::a);
      EXPECT_EQ(c.triangle, 0);
      EXPECT_NEAR(c.origin.z(), -0.1, 1e-7);
      EXPECT_NEAR(c.depth, nearest ? 0.1 : 0.1 * std::sqrt(3.0), 1e-6);
      EXPECT_NEAR(c.projected_depth, 0.1, 1e-6);
      EXPECT_NEAR((c.normal - Eigen::Vector3d::UnitZ()).norm(), 0.0, 1e-7);
      EXPECT_NEAR((c.push - Eigen::Vector3d(0, 0, 0.1)).norm(), 0.0, 1e-6);
    }
    EXPECT_TRUE(res.pairs[0].colliding);
  }
}

// A tilted ground: the plane through the ground's origin, normal along its
// local +z; a sphere sunk by 0.2 along that normal has rays whose exit lies on
// the plane, and a sphere above it within the extension is tracked, not hit.
TEST_P(Conformance, SphereOnTiltedHalfSpace) {
  const Eigen::Quaterniond tilt(Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitX()));
  const Eigen::Vector3d n = tilt * Eigen::Vector3d::UnitZ();
  auto r = rig(std::make_shared<Shape>(Sphere{1.0}), std::make_shared<Shape>(HalfSpace{}));
  const StepResult sunk = r.step(at(Eigen::Vector3d(n * 0.8), Eigen::Quaterniond::Identity()), at(Eigen::Vector3d::Zero(), tilt));
  ASSERT_FALSE(sunk.contacts.empty());
  double deepest = 0;
  for (const Contact& c : sunk.contacts) {
    EXPECT_NEAR(n.dot(c.origin + c.depth * c.direction), 0.0, 1e-5);
    EXPECT_NEAR((c.normal - n).norm(), 0.0, 1e-6);
    deepest = std::max(deepest, c.projected_depth);
  }
  // No origin is exactly at the lowest point: the deepest is a little short.
  EXPECT_LE(deepest, 0.2 + 1e-7);
  EXPECT_GT(deepest, 0.19);
  const StepResult above = r.step(at(Eigen::Vector3d(n * 1.05), Eigen::Quaterniond::Identity()), at(Eigen::Vector3d::Zero(), tilt));
  EXPECT_TRUE(above.contacts.empty());
  EXPECT_FALSE(above.predictive.empty());
}

// A body reaching below the ground by more than a box ground's thickness
// still leaves through the plane: depth is the height below it.
TEST_P(Conformance, DeepInHalfSpaceStillLeavesThroughThePlane) {
  auto r = rig(box_mesh(0.5), std::make_shared<Shape>(HalfSpace{}));
  const StepResult res = r.step(at(0, 0, -20), at(0, 0, 0));
  ASSERT_EQ(res.contacts.size(), 4u);  // the top corners' inward rays point down: they never leave
  for (const Contact& c : res.contacts) EXPECT_NEAR(c.projected_depth, 20.5, 1e-4);
}

// A small cube in the opening of a U: its vertices lie inside the bounding-box
// overlap but outside the U's body, so nothing collides; moved into an arm,
// all eight collide.
TEST_P(Conformance, ConcaveOpeningIsNotInside) {
  auto r = rig(shape(gen::u_shape()), box_mesh(0.25));
  const StepResult open = r.step(Pose{}, at(0.05, 0.5, 0.1));
  EXPECT_FALSE(open.pairs[0].colliding);
  EXPECT_GE(open.stats.candidates, 8u);
  auto r2 = rig(shape(gen::u_shape()), box_mesh(0.25));
  const StepResult arm = r2.step(Pose{}, at(1.0, 0.5, 0.1));
  size_t from_cube = 0;
  for (const Contact& c : arm.contacts) from_cube += c.source == Side::b;
  EXPECT_EQ(from_cube, 8u);
}

TEST_P(Conformance, ProjectedDepthIsDepthTimesCosine) {
  Config c;
  c.projected = false;
  auto r = rig(shape(gen::concave_blob(902, 1)), shape(gen::concave_blob(902, 2)), c);
  const StepResult res = r.step(Pose{}, at(Eigen::Vector3d(1.1, 0.2, 0.1), Eigen::Quaterniond(0.9, 0.1, 0.3, 0.2)));
  ASSERT_GT(res.contacts.size(), 10u);
  for (const Contact& k : res.contacts) {
    EXPECT_NEAR(k.projected_depth, k.depth * std::abs(k.direction.dot(k.normal)), 1e-12);
    EXPECT_LE(k.projected_depth, k.depth + 1e-12);
    EXPECT_NEAR((k.push - k.direction * k.depth).norm(), 0.0, 1e-12);  // projection off: push along the ray
  }
}

// Convex pairs in shallow contact (the small intersection volumes of
// section 2.1.5): after a motion below displacement_threshold from a full
// step, the iterative step finds the same penetrating vertices as full.
TEST_P(Conformance, IterativeMatchesFullAfterSmallMotion) {
  std::mt19937 g(21);
  std::uniform_real_distribution<double> u(-1, 1);
  Config iterative;
  iterative.mode = Mode::iterative;
  Config full;
  full.mode = Mode::full;
  auto ico = shape(gen::icosphere(0.6, 3));
  auto box = box_mesh(0.5);
  size_t contacts = 0;
  for (int i = 0; i < 40; ++i) {
    const bool use_box = i % 2 == 1;
    // B's icosphere overlaps A's face or sphere by 0.01 to 0.05.
    const Eigen::Vector3d dir = use_box ? Eigen::Vector3d::UnitX() : Eigen::Vector3d(u(g), u(g), u(g)).normalized();
    const Eigen::Vector3d offset = use_box ? Eigen::Vector3d(0, 0.3 * u(g), 0.3 * u(g)) : Eigen::Vector3d::Zero();
    const double reach = use_box ? 0.5 : 0.6;
    const Eigen::Vector3d center = offset + (reach + 0.6 - (0.03 + 0.02 * u(g))) * dir;
    const Pose b0 = at(center, Eigen::Quaterniond(1, 0.3 * u(g), 0.3 * u(g), 0.3 * u(g)));
    // A small motion: 0.01 of translation, under the 0.05 threshold.
    const Pose b1 = at(b0.position + 0.01 * Eigen::Vector3d(u(g), u(g), u(g)).normalized(), b0.orientation);
    auto it = rig(use_box ? box : ico, ico, iterative);
    it.step(Pose{}, b0);
    const StepResult walked = it.step(Pose{}, b1);
    ASSERT_EQ(walked.pairs[0].mode, PairMode::iterative);
    auto fu = rig(use_box ? box : ico, ico, full);
    const StepResult traced = fu.step(Pose{}, b1);
    EXPECT_EQ(penetrating(walked), penetrating(traced)) << "case " << i;
    if (penetrating(walked) == penetrating(traced)) {
      for (size_t k = 0; k < traced.contacts.size(); ++k)
        EXPECT_NEAR(walked.contacts[k].depth, traced.contacts[k].depth, 1e-9);
    }
    contacts += traced.contacts.size();
  }
  EXPECT_GT(contacts, 100u);
}

TEST_P(Conformance, LargeMotionSendsThePairBackToFull) {
  auto r = rig(box_mesh(0.5), box_mesh(0.6), hand_computed());  // automatic mode, threshold 0.05
  EXPECT_EQ(r.step(Pose{}, at(1.0, 0, 0)).pairs[0].mode, PairMode::full);
  const StepResult small = r.step(Pose{}, at(0.98, 0, 0));
  EXPECT_EQ(small.pairs[0].mode, PairMode::iterative);
  EXPECT_EQ(small.stats.rays_iterative, 4u);
  const StepResult large = r.step(Pose{}, at(0.9, 0, 0));  // 0.1 from the last full step
  EXPECT_EQ(large.pairs[0].mode, PairMode::full);
  EXPECT_EQ(large.stats.fallbacks_to_full, 1u);
  // A rotation counts too: 0.06 rad times the larger radius (~1.04) exceeds 0.05.
  const Pose turned = at(Eigen::Vector3d::Zero(), Eigen::Quaterniond(Eigen::AngleAxisd(0.06, Eigen::Vector3d::UnitZ())));
  EXPECT_EQ(r.step(turned, at(0.9, 0, 0)).pairs[0].mode, PairMode::full);
}

// Figure 2.4, first row, fixed: B (half 0.6) approaches A (half 0.5); at
// step 0 (full) nothing touches but A's +x vertices are 0.03 from B's face,
// within distance_extension; at step 1 (iterative, B moved 0.04) they are
// 0.01 inside and reported at once through predictive rays. Without
// predictive rays the same step reports nothing: the delay.
TEST_P(Conformance, PredictiveRaysCatchNewContactsInIterativeSteps) {
  for (bool predictive : {true, false}) {
    Config c;
    c.predictive = predictive;
    auto r = rig(box_mesh(0.5), box_mesh(0.6), c);
    const StepResult s0 = r.step(Pose{}, at(1.13, 0, 0));
    EXPECT_FALSE(s0.pairs[0].colliding);
    EXPECT_EQ(s0.predictive.size(), predictive ? 4u : 0u);
    for (const PredictiveRay& p : s0.predictive) EXPECT_NEAR(p.distance, 0.03 * std::sqrt(3.0), 1e-6);
    const StepResult s1 = r.step(Pose{}, at(1.09, 0, 0));
    ASSERT_EQ(s1.pairs[0].mode, PairMode::iterative);
    if (predictive) {
      // A's four corners, and B's face diagonal: watched, so tested again.
      ASSERT_EQ(s1.contacts.size(), 5u);
      for (const Contact& k : s1.contacts) EXPECT_NEAR(k.projected_depth, 0.01, 1e-6);
      EXPECT_EQ(s1.contacts.back().kind, ContactKind::edge);
    } else {
      EXPECT_EQ(s1.contacts.size(), 0u) << "without predictive rays the contact is delayed";
    }
  }
}

TEST_P(Conformance, PairAbsentFromAStepIsEvicted) {
  auto r = rig(box_mesh(0.5), box_mesh(0.6));
  r.step(Pose{}, at(1.0, 0, 0));
  r.narrow->detect({});  // the pair left the broad phase
  const StepResult back = r.step(Pose{}, at(1.0, 0, 0));
  EXPECT_EQ(back.pairs[0].mode, PairMode::full) << "a returning pair starts afresh";
}

TEST_P(Conformance, BadCallsAreUsageErrors) {
  auto r = rig(box_mesh(0.5), box_mesh(0.6));
  const BodyPair self{r.a, r.a}, unknown{r.a, 99};
  EXPECT_THROW(r.narrow->detect(std::span(&self, 1)), UsageError);
  EXPECT_THROW(r.narrow->detect(std::span(&unknown, 1)), UsageError);
  const BodyPair twice[2] = {{r.a, r.b}, {r.b, r.a}};
  EXPECT_THROW(r.narrow->detect(twice), UsageError);
  Pose bad;
  bad.orientation = Eigen::Quaterniond(2, 0, 0, 0);
  EXPECT_THROW(r.narrow->set_pose(r.a, bad), UsageError);
}

// detect in two halves: the same steps as detect, bit for bit, while the
// caller works (it polls detect_done, and some polls find the step still
// running: the caller ran while the step did); bad pairs throw at
// detect_begin and lose nothing; every other call before detect_end is a
// UsageError.
TEST_P(Conformance, BegunStepsEqualDetectWhileTheCallerWorks) {
  const validation::Family f = validation::make_family("concave");
  Config config;
  config.mode = Mode::automatic;
  auto sync = make_narrow_phase(GetParam(), config), begun = make_narrow_phase(GetParam(), config);
  std::vector<BodyPair> pairs;
  std::vector<validation::PosePair> poses;
  for (NarrowPhase* n : {sync.get(), begun.get()}) {
    const ShapeId sa = n->add_shape(f.a), sb = n->add_shape(f.b);
    pairs.clear();
    poses.clear();
    for (size_t i = 0; i < 32; ++i) {
      poses.push_back(validation::random_poses(f, 3, i));
      pairs.push_back({n->add_body(sa, poses[i].a), n->add_body(sb, poses[i].b)});
    }
  }
  std::vector<StepResult> expected, got;
  size_t polls_running = 0;
  for (size_t step = 0; step < 4; ++step) {
    for (size_t i = 0; i < pairs.size(); ++i) {
      if (step > 0) poses[i] = validation::moved(f, poses[i], f.step_motion(), 3, step * pairs.size() + i);
      for (NarrowPhase* n : {sync.get(), begun.get()}) {
        n->set_pose(pairs[i].a, poses[i].a);
        n->set_pose(pairs[i].b, poses[i].b);
      }
    }
    expected.push_back(sync->detect(pairs));
    StepResult& out = got.emplace_back();
    begun->detect_begin(pairs, out);
    while (!begun->detect_done()) ++polls_running;
    EXPECT_THROW(begun->set_pose(pairs[0].a, poses[0].a), UsageError);
    EXPECT_THROW(begun->detect(pairs), UsageError);
    EXPECT_THROW(begun->detect_begin(pairs, out), UsageError);
    begun->detect_end();
  }
  EXPECT_GT(expect_same_run(got, expected), 0u);
  EXPECT_GT(polls_running, 0u) << "every step had ended before the caller looked";
  EXPECT_THROW(begun->detect_end(), UsageError) << "no step begun";
  EXPECT_THROW(begun->detect_done(), UsageError);
  // Bad pairs throw at the start and lose nothing: the next step walks on.
  const BodyPair self{pairs[0].a, pairs[0].a};
  StepResult out;
  EXPECT_THROW(begun->detect_begin(std::span(&self, 1), out), UsageError);
  begun->detect_begin(pairs, out);
  begun->detect_end();
  EXPECT_GT(out.stats.pairs_iterative, 0u);
}

// Same penetrating vertices, same triangles, depths within 1e-5 relative as
// the basic traversal, on concave pairs, in full and in iterative steps.
// Every backend but basic itself.
class ConformanceBesideBasic : public Conformance {};

TEST_P(ConformanceBesideBasic, AgreesWithBasic) {
  auto blob_a = shape(gen::concave_blob(902, 1));
  auto blob_b = shape(gen::concave_blob(902, 2));
  std::mt19937 g(33);
  std::uniform_real_distribution<double> u(-1, 1);
  size_t contacts = 0;
  for (int i = 0; i < 20; ++i) {
    const Pose a = at(Eigen::Vector3d(u(g), u(g), u(g)), Eigen::Quaterniond(1, u(g), u(g), u(g)));
    const Pose b = at(a.position + 1.3 * Eigen::Vector3d(u(g), u(g), u(g)).normalized(),
                      Eigen::Quaterniond(1, u(g), u(g), u(g)));
    const Pose b1 = at(b.position + Eigen::Vector3d(0.01, -0.01, 0.005), b.orientation);
    PairRig mine(GetParam(), blob_a, blob_b), reference("basic", blob_a, blob_b);
    for (int step = 0; step < 2; ++step) {
      const Pose& pb = step == 0 ? b : b1;
      const StepResult x = mine.step(a, pb), y = reference.step(a, pb);
      ASSERT_EQ(x.pairs[0].mode, y.pairs[0].mode);
      // The first step traces in full; the second, 1.5 cm on, walks.
      ASSERT_EQ(x.pairs[0].mode, step == 0 ? PairMode::full : PairMode::iterative) << "case " << i;
      ASSERT_EQ(x.contacts.size(), y.contacts.size()) << "case " << i;
      for (size_t k = 0; k < x.contacts.size(); ++k) {
        EXPECT_EQ(x.contacts[k].source, y.contacts[k].source);
        EXPECT_EQ(x.contacts[k].vertex, y.contacts[k].vertex);
        EXPECT_EQ(x.contacts[k].triangle, y.contacts[k].triangle) << "case " << i << " vertex " << x.contacts[k].vertex;
        EXPECT_NEAR(x.contacts[k].depth, y.contacts[k].depth, 1e-5 * std::max(1e-3, y.contacts[k].depth));
      }
      EXPECT_EQ(x.predictive.size(), y.predictive.size());
      contacts += x.contacts.size();
    }
  }
  EXPECT_GT(contacts, 500u) << "too few contacts: the comparison would be vacuous";
}

TEST_P(Conformance, SameContactsBitForBitAcrossThreadCounts) {
  auto blob = shape(gen::concave_blob(902, 1));
  auto run = [&] {
    PairRig r(GetParam(), blob, blob);
    return r.step(Pose{}, at(Eigen::Vector3d(0.9, 0.3, 0.2), Eigen::Quaterniond(0.8, 0.3, 0.1, 0.4)));
  };
  const StepResult many = run();
  StepResult one;
  {
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, 1);
    one = run();
  }
  ASSERT_GT(many.contacts.size(), 0u);
  expect_same_step(many, one, "all threads against one");
}

// A step of many pairs gives each pair what a step of that pair alone
// gives: a large batch may trace its rays another way than a small one (the
// CPU executor traces them as it selects them, block by block).
TEST_P(Conformance, SameContactsInABatchAsAlone) {
  auto blob_a = shape(gen::concave_blob(902, 1));
  auto blob_b = shape(gen::concave_blob(902, 2));
  Config full;
  full.mode = Mode::full;
  auto narrow = make_narrow_phase(GetParam(), full);
  const ShapeId sa = narrow->add_shape(blob_a), sb = narrow->add_shape(blob_b);
  std::mt19937 g(7);
  std::uniform_real_distribution<double> u(-1, 1);
  std::vector<BodyPair> pairs;
  for (int i = 0; i < 64; ++i) {  // 128 jobs: 8 blocks of 16
    const Pose a = at(Eigen::Vector3d(10.0 * i, 0, 0), Eigen::Quaterniond(1, u(g), u(g), u(g)).normalized());
    const Pose b = at(a.position + 1.3 * Eigen::Vector3d(u(g), u(g), u(g)).normalized(),
                      Eigen::Quaterniond(1, u(g), u(g), u(g)).normalized());
    pairs.push_back({narrow->add_body(sa, a), narrow->add_body(sb, b)});
  }
  const StepResult batch = narrow->detect(pairs);
  size_t contacts = 0;
  for (size_t i = 0; i < pairs.size(); ++i) {
    const StepResult alone = narrow->detect(std::span(&pairs[i], 1));
    const PairResult& p = batch.pairs[i];
    ASSERT_EQ(p.contact_count, alone.contacts.size()) << "pair " << i;
    ASSERT_EQ(p.predictive_count, alone.predictive.size()) << "pair " << i;
    const auto mine = batch.contacts_of(p);
    for (size_t k = 0; k < mine.size(); ++k) {
      EXPECT_EQ(mine[k].vertex, alone.contacts[k].vertex);
      EXPECT_EQ(mine[k].triangle, alone.contacts[k].triangle);
      EXPECT_EQ(mine[k].depth, alone.contacts[k].depth);
    }
    contacts += mine.size();
  }
  EXPECT_GT(contacts, 500u) << "too few contacts: the comparison would be vacuous";
}

// The step's statistics agree with one another and with its records, in
// full and in iterative steps: every candidate is one inward ray or one
// walk, every walk ends one way, and rays that report and track nothing
// count all the same.
TEST_P(Conformance, StatisticsAddUp) {
  auto blob_a = shape(gen::concave_blob(902, 1));
  auto blob_b = shape(gen::concave_blob(902, 2));
  for (const Mode mode : {Mode::full, Mode::iterative}) {
    Config config;
    config.mode = mode;
    auto narrow = make_narrow_phase(GetParam(), config);
    const ShapeId sa = narrow->add_shape(blob_a), sb = narrow->add_shape(blob_b);
    std::vector<BodyPair> pairs;
    for (int i = 0; i < 8; ++i)
      pairs.push_back({narrow->add_body(sa, at(10.0 * i, 0, 0)), narrow->add_body(sb, at(10.0 * i + 1.2, 0.1, 0.05))});
    for (int step = 0; step < 3; ++step) {
      SCOPED_TRACE(std::string(to_string(mode)) + ", step " + std::to_string(step));
      const StepResult r = narrow->detect(pairs);
      const StepStats& s = r.stats;
      size_t contacts = 0, predictive = 0;
      for (const PairResult& p : r.pairs) {
        contacts += p.contact_count;
        predictive += p.predictive_count;
      }
      EXPECT_GT(r.contacts.size(), 0u);
      EXPECT_EQ(contacts, r.contacts.size());
      EXPECT_EQ(predictive, r.predictive.size());
      EXPECT_EQ(s.candidates, s.rays_full + s.rays_iterative);
      EXPECT_GE(s.edge_rays, s.edges_tested - s.edges_skipped);
      if (mode == Mode::full || step == 0) {
        EXPECT_EQ(s.edges_skipped, 0u);
      }
      EXPECT_LE(s.edge_contacts, s.edges_tested);
      size_t edge_contacts = 0;
      for (const Contact& c : r.contacts) edge_contacts += c.kind == ContactKind::edge;
      EXPECT_EQ(edge_contacts, s.edge_contacts);
      size_t endings = 0;
      for (size_t e : s.walk_endings) endings += e;
      EXPECT_EQ(endings, s.rays_iterative);
      if (mode == Mode::full) {
        // Nothing is watched in full mode, and most candidates report nothing.
        EXPECT_EQ(s.rays_watched, 0u);
        EXPECT_GT(s.rays_full, 2 * (r.contacts.size() + r.predictive.size()));
      } else if (step == 0) {
        EXPECT_EQ(s.rays_iterative, 0u);
        EXPECT_GE(s.rays_full + s.edges_tested, r.contacts.size() + r.predictive.size() + s.rays_watched);
      } else {
        EXPECT_EQ(s.rays_full, 0u);
        EXPECT_GT(s.rays_iterative, 0u);
        EXPECT_GE(s.walk_steps, s.rays_iterative);
      }
    }
  }
}

INSTANTIATE_TEST_SUITE_P(Backends, Conformance, ::testing::ValuesIn(usable_backends()),
                         [](const auto& info) { return test_name(info.param); });
INSTANTIATE_TEST_SUITE_P(Backends, ConformanceBesideBasic, ::testing::ValuesIn(backends_beside_basic()),
                         [](const auto& info) { return test_name(info.param); });

TEST(Registry, UnknownBackendListsWhatIsAvailable) {
  try {
    make_narrow_phase("warp-drive");
    ADD_FAILURE();
  } catch (const BackendError& e) {
    EXPECT_NE(std::string(e.what()).find("warp-drive"), std::string::npos);
    EXPECT_NE(std::string(e.what()).find("basic"), std::string::npos);
  }
}

TEST(Registry, AutoPicksAUsableBackendAndSaysWhich) {
  auto n = make_narrow_phase("auto");
  EXPECT_NE(n->name(), "auto");
  EXPECT_FALSE(n->devices().empty());
}

TEST(Registry, BadConfigIsRejected) {
  Config c;
  c.displacement_threshold = 1.0;
  c.distance_extension = 0.5;
  EXPECT_THROW(make_narrow_phase("basic", c), ConfigError);
}

}  // namespace
}  // namespace rtcd::test
