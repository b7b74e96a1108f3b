// The simulation host on small scenes that finish in seconds: each effect
// checked by what it does to the bodies with it listed and without (gravity,
// contacts, friction, restitution, predictive, speculative, projected,
// interpenetration), resting, stacking, the stages' work counters, bad
// scenes, reproducibility.
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <numbers>

#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include "rtcd/sim/recording.hpp"
#include "rtcd/sim/simulation.hpp"
#include "support_sim.hpp"

namespace rtcd::test {
namespace {

using sim::Effect;
using sim::Simulation;

constexpr double kG = 9.81;

// A box of half extent 0.25 resting on the ground keeps its height.
TEST(Sim, BoxRestsOnTheGround) {
  Simulation s(scene_from(R"({
    "time_step": 0.004166666666666667, "steps": 1000,
    "effects": ["gravity", "contacts", "friction", "predictive", "projected"],
    "bodies": [{"box": [0.25, 0.25, 0.25], "mass": 2, "pose": {"position": [0, 0, 0.25]}}]
  })"));
  double worst = 0;
  for (int i = 0; i < 1000; ++i) {
    s.step();
    worst = std::max(worst, std::abs(s.bodies()[0].pose.position.z() - 0.25));
  }
  EXPECT_LT(worst, 1e-3);
}

// A sphere of radius 0.5 dropped from 1 m (lowest point) with restitution
// e = 0.8 bounces to e² h; without the effect it does not bounce. At 1 kHz
// the impact speed of 4.4 m/s moves 4.4 mm a step; predictive rays find the
// impact on the step it happens, so it is never deeper than that step's
// motion (under 1% of the radius: 5 mm).
TEST(Sim, SphereBouncesToRestitutionSquaredTimesHeightOnlyWithRestitution) {
  const double e = 0.8, h = 1.0, r = 0.5;
  for (bool restitution : {true, false}) {
    const std::string effects = restitution ? R"(["gravity", "contacts", "restitution", "predictive", "projected"])"
                                            : R"(["gravity", "contacts", "predictive", "projected"])";
    Simulation s(scene_from(R"({
      "time_step": 0.001, "steps": 2000, "effects": )" + effects + R"(,
      "ground": {"restitution": 1.0},
      "bodies": [{"sphere": 0.5, "mass": 1, "restitution": 0.8, "pose": {"position": [0, 0, 1.5]}}]
    })"));
    bool bounced = false;
    double peak = 0, deepest = 0;
    for (int i = 0; i < 2000; ++i) {
      s.step();
      const auto b = s.bodies()[0];
      deepest = std::max(deepest, r - b.pose.position.z());
      if (b.linear_velocity.z() > 0) bounced = true;
      if (bounced) peak = std::max(peak, b.pose.position.z() - r);
    }
    EXPECT_LT(deepest, 0.01 * r);
    if (restitution) {
      ASSERT_TRUE(bounced);
      EXPECT_NEAR(peak, e * e * h, 0.1 * e * e * h);
      EXPECT_GT(s.counters().restitution_points, 0u);
    } else {
      EXPECT_LT(peak, 0.01 * h) << "rose again without restitution";
      EXPECT_EQ(s.counters().restitution_points, 0u);
    }
  }
}

// A concave U dropped onto another resting on the ground: both end at rest,
// stacked, and no pair is deeper than 2% of the U's size.
TEST(Sim, ConcaveBodyFallsOnAnotherAndRests) {
  Simulation s(scene_from(R"({
    "time_step": 0.008333333333333333, "steps": 480,
    "effects": ["gravity", "contacts", "friction", "predictive", "speculative", "projected", "interpenetration"],
    "interpenetration": {"every": 1000},
    "narrow_phase": {"distance_extension": 0.05, "displacement_threshold": 0.02},
    "bodies": [
      {"name": "lower", "mesh": "../meshes/u_shape.obj", "scale": 0.5, "pose": {"position": [0, 0, 0.3]}},
      {"name": "upper", "mesh": "../meshes/u_shape.obj", "scale": 0.5,
       "pose": {"position": [0.1, 0.05, 1.5], "orientation": [0.99, 0.05, 0.08, 0.1]}}
    ]
  })"));
  for (int i = 0; i < 480; ++i) s.step();
  const sim::StepRecord& last = s.last();
  const double size = 1.5;  // the scaled U is 1.5 wide, 0.5 thick
  ASSERT_GE(last.interpenetration, 0);
  EXPECT_LT(last.deepest, 0.02 * size);
  for (const PairResult& p : s.last_narrow_phase().pairs) EXPECT_LT(p.max_depth, 0.02 * size);
  const auto bodies = s.bodies();
  EXPECT_GT(bodies[1].pose.position.z(), bodies[0].pose.position.z() + 0.2) << "the upper U rests on the lower";
  for (const auto& b : bodies) {
    EXPECT_LT(b.linear_velocity.norm(), 1e-2) << b.label;
    EXPECT_LT(b.angular_velocity.norm(), 1e-2) << b.label;
  }
}

// Two planks dropped crosswise: no corner of either is ever inside the
// other, only edges cross, so without edge contacts the upper one falls
// through the lower one to the ground; with them it rests on it.
TEST(Sim, PlanksDroppedCrosswiseRestOneOnTheOther) {
  const auto upper_height = [](bool edges) {
    Simulation s(scene_from(std::string(R"({
      "time_step": 0.004166666666666667, "steps": 600,
      "effects": ["gravity", "contacts", "friction", "predictive", "projected"],
      "narrow_phase": {"edge_contacts": )") + (edges ? "true" : "false") + R"(},
      "bodies": [
        {"name": "lower", "box": [1.0, 0.1, 0.05], "mass": 2, "pose": {"position": [0, 0, 0.05]}},
        {"name": "upper", "box": [0.1, 1.0, 0.05], "mass": 2, "pose": {"position": [0, 0, 0.3]}}
      ]
    })"));
    for (int i = 0; i < 600; ++i) s.step();
    const auto bodies = s.bodies();
    if (edges) {
      EXPECT_LT(bodies[1].linear_velocity.norm(), 1e-2);
      EXPECT_LT(s.last().deepest, 0.005);
    }
    return bodies[1].pose.position.z();
  };
  EXPECT_NEAR(upper_height(true), 0.15, 0.005) << "resting on the lower plank's top (0.1) by its half thickness";
  EXPECT_LT(upper_height(false), 0.1) << "without edge contacts the planks pass through each other";
}

// A ring dropped over a fixed thin peg hangs on it. The ring is turned
// half a segment about the peg, so no vertex of its hole's rim lands on the
// peg (0.02 wide; the rim's vertices 0.0255 apart): the peg's edges crossing
// the ring's tube hold it, and without edge contacts it falls through.
TEST(Sim, RingOnAPegStaysLinked) {
  const auto run = [](bool edges) {
    // torus.obj scaled by 0.3: radius 0.3, tube 0.105, hole 0.195. Its axis
    // along x, the peg's; the peg's top at 1.01.
    Simulation s(scene_from(std::string(R"({
      "time_step": 0.004166666666666667, "steps": 1200,
      "effects": ["gravity", "contacts", "friction", "predictive", "projected"],
      "narrow_phase": {"edge_contacts": )") + (edges ? "true" : "false") + R"(},
      "bodies": [
        {"name": "peg", "box": [1.0, 0.01, 0.01], "static": true, "pose": {"position": [0, 0, 1.0]}},
        {"name": "ring", "mesh": "../meshes/torus.obj", "scale": 0.3, "mass": 1,
         "pose": {"position": [0, 0, 1.0],
                  "orientation": [0.70672818736035359, 0.023135885337482186, 0.70672818736035348, 0.023135885337482183]}}
      ]
    })"));
    double worst = 0;  // how far the ring's centre strayed from the peg's axis
    for (int i = 0; i < 1200; ++i) {
      s.step();
      const Eigen::Vector3d c = s.bodies()[1].pose.position;
      worst = std::max(worst, std::hypot(c.y(), c.z() - 1.0));
    }
    return std::pair{worst, s.bodies()[1]};
  };
  const auto [worst, ring] = run(true);
  // The peg stays in the hole: the rim sinks into the peg on impact (1.9
  // m/s, 8 mm a step) by less than the peg's half width, and the ring hangs
  // with the rim on the peg's top.
  EXPECT_LT(worst, 0.195);
  // It may still swing about the peg (a pendulum on a thin rod loses little).
  EXPECT_NEAR(ring.pose.position.z(), 1.01 - 0.195, 0.01) << "hanging by its hole's top on the peg's top";
  EXPECT_LT(run(false).second.pose.position.z(), 0.5) << "without edge contacts the ring falls through the peg";
}

// Predictive rays (thesis 2.1.3): a vertex about to penetrate is tracked, so
// the penetration is found on the next narrow phase after it happens, not at
// the pair's next full step. A box sinks at 0.01 per step into the ground;
// with displacement_threshold 0.2 its pair stays iterative for 20 steps.
TEST(Sim, PredictiveRaysFindAPenetrationOnTheStepItHappens) {
  for (bool predictive : {true, false}) {
    const std::string effects = predictive ? R"(["contacts", "predictive", "projected"])" : R"(["contacts", "projected"])";
    Simulation s(scene_from(R"({"time_step": 0.016666666666666666, "steps": 40, "effects": )" + effects + R"(,
      "narrow_phase": {"distance_extension": 0.2, "displacement_threshold": 0.2},
      "bodies": [{"box": [0.25, 0.25, 0.25], "mass": 1, "velocity": [0, 0, -0.6], "pose": {"position": [0, 0, 0.345]}}]})"));
    int penetrated = -1, found = -1;
    for (int i = 0; i < 40 && found < 0; ++i) {
      if (s.step().contacts > 0) found = i;
      if (penetrated < 0 && s.bodies()[0].pose.position.z() < 0.25) penetrated = i;
    }
    ASSERT_GE(penetrated, 0);
    if (predictive)
      EXPECT_EQ(found, penetrated + 1) << "seen by the step after the one that moved it in";
    else
      EXPECT_GT(found, penetrated + 5) << "found only at the next full step";
  }
}

// Bullet's sleeping skips the pairs of resting bodies; a scene says whether
// it may (the thesis experiments run without).
TEST(Sim, SleepingIsTheScenesChoice) {
  for (bool sleeping : {true, false}) {
    Simulation s(scene_from(std::string(R"({"time_step": 0.008333333333333333, "steps": 480, "sleeping": )") +
                            (sleeping ? "true" : "false") + R"(,
      "effects": ["gravity", "contacts", "friction", "predictive", "speculative", "projected"],
      "narrow_phase": {"distance_extension": 0.05, "displacement_threshold": 0.02},
      "bodies": [{"box": [0.25, 0.25, 0.25], "mass": 1, "pose": {"position": [0, 0, 0.26]}}]})"));
    for (int i = 0; i < 480; ++i) s.step();
    EXPECT_EQ(s.last().pairs, sleeping ? 0u : 1u) << (sleeping ? "asleep" : "awake");
    EXPECT_NEAR(s.bodies()[0].pose.position.z(), 0.25, 2e-3);
  }
}

// A box released on a 30° slope slides d = ½ g (sin θ − μ cos θ) t² with
// Coulomb friction μ, and ½ g sin θ t² without friction.
TEST(Sim, FrictionOnASlopeFollowsCoulomb) {
  const double theta = std::numbers::pi / 6, t = 1.0;
  for (bool friction : {true, false}) {
    const double mu = 0.3;
    const std::string effects = friction ? R"(["gravity", "contacts", "friction", "predictive", "projected"])"
                                         : R"(["gravity", "contacts", "predictive", "projected"])";
    const Eigen::Vector3d n(0, -std::sin(theta), std::cos(theta));
    const Eigen::Quaterniond tilt = Eigen::Quaterniond::FromTwoVectors(Eigen::Vector3d::UnitZ(), n);
    const Eigen::Vector3d start = n * 0.2501;
    char json[1024];
    std::snprintf(json, sizeof json, R"({
      "time_step": 0.004166666666666667, "steps": 240, "effects": %s,
      "ground": {"normal": [0, %.17g, %.17g], "friction": 1.0},
      "bodies": [{"box": [0.25, 0.25, 0.25], "mass": 1, "friction": %.17g,
                  "pose": {"position": [%.17g, %.17g, %.17g], "orientation": [%.17g, %.17g, %.17g, %.17g]}}]
    })", effects.c_str(), n.y(), n.z(), mu, start.x(), start.y(), start.z(), tilt.w(), tilt.x(), tilt.y(), tilt.z());
    Simulation s(scene_from(json));
    for (int i = 0; i < 240; ++i) s.step();
    const double slid = (s.bodies()[0].pose.position - start).norm();
    const double expected = 0.5 * kG * (std::sin(theta) - (friction ? mu * std::cos(theta) : 0.0)) * t * t;
    EXPECT_NEAR(slid, expected, 0.1 * expected) << (friction ? "with" : "without") << " friction";
    if (friction)
      EXPECT_GT(s.counters().friction_points, 0u);
    else
      EXPECT_EQ(s.counters().friction_points, 0u);
  }
}

// Gravity is the scene's vector, applied to every dynamic body and to no
// static one: free fall under Bullet's semi-implicit Euler, v_n = g n dt and
// x_n = x_0 + g dt² n(n+1)/2. Unlisted, nothing moves.
TEST(Sim, GravityAcceleratesDynamicBodiesByTheScenesVector) {
  const Eigen::Vector3d g(0.5, -1.0, -3.0);
  const double dt = 0.01;
  const int n = 60;
  for (bool gravity : {true, false}) {
    Simulation s(scene_from(std::string(R"({"time_step": 0.01, "steps": 60, "ground": false, "gravity": [0.5, -1, -3],
      "effects": )") + (gravity ? R"(["gravity"])" : "[]") + R"(,
      "bodies": [{"box": [0.25, 0.25, 0.25], "mass": 2, "pose": {"position": [0, 0, 1]}},
                 {"box": [0.25, 0.25, 0.25], "static": true, "pose": {"position": [3, 0, 0]}}]})"));
    for (int i = 0; i < n; ++i) s.step();
    const auto bodies = s.bodies();
    const Eigen::Vector3d v = gravity ? Eigen::Vector3d(g * n * dt) : Eigen::Vector3d::Zero();
    const Eigen::Vector3d x = Eigen::Vector3d(0, 0, 1) + (gravity ? Eigen::Vector3d(g * dt * dt * n * (n + 1) / 2) : Eigen::Vector3d::Zero());
    EXPECT_LT((bodies[0].linear_velocity - v).norm(), 1e-5) << bodies[0].linear_velocity.transpose();
    EXPECT_LT((bodies[0].pose.position - x).norm(), 1e-5) << bodies[0].pose.position.transpose();
    EXPECT_EQ(bodies[1].pose.position, Eigen::Vector3d(3, 0, 0)) << "a static body does not fall";
    EXPECT_EQ(s.counters().gravity_forces, gravity ? uint64_t(n) : 0u) << "once per dynamic body and step";
  }
}

// The counters count each stage's work where it is done, so an unlisted
// effect is seen doing nothing where it would have work: a box landing on
// the ground with friction and restitution coefficients and predictive rays
// to make speculative points from. The box starts 0.05 above the ground, its
// corner rays 0.087 from it: an extension of 0.1 tracks them from the first
// step (a derived one, a tenth of the box's radius, would first see them
// once they touch).
TEST(Sim, StagesCountTheirWorkAndUnlistedOnesDoNone) {
  const std::string rest = R"("interpenetration": {"every": 5}, "ground": {"restitution": 1.0},
    "narrow_phase": {"distance_extension": 0.1, "displacement_threshold": 0.05},
    "bodies": [{"box": [0.25, 0.25, 0.25], "friction": 0.5, "restitution": 0.5, "pose": {"position": [0, 0, 0.3]}}]})";
  {
    Simulation s(scene_from(R"({"steps": 20, "effects": ["gravity"], )" + rest));
    for (int i = 0; i < 20; ++i) s.step();
    const sim::StageCounters& c = s.counters();
    EXPECT_EQ(c.gravity_forces, 20u);
    EXPECT_EQ(c.narrow_phase_batches, 0u);
    EXPECT_EQ(c.friction_points + c.restitution_points + c.speculative_points + c.interpenetration_passes + c.snapshots, 0u);
    EXPECT_EQ(s.backend(), "none") << "no narrow phase is even made";
    EXPECT_LT(s.bodies()[0].pose.position.z(), 0.0) << "without contacts it falls through the ground";
  }
  {
    Simulation s(scene_from(R"({"steps": 20, "effects": ["contacts"], )" + rest));
    for (int i = 0; i < 20; ++i) s.step();
    EXPECT_EQ(s.counters().gravity_forces, 0u);
    EXPECT_EQ(s.counters().narrow_phase_batches, 20u);
    EXPECT_NEAR(s.bodies()[0].pose.position.z(), 0.3, 1e-6) << "without gravity it stays put";
  }
  for (bool listed : {false, true}) {
    const std::string effects = listed ? R"(["gravity", "contacts", "friction", "restitution", "predictive", "speculative",
                                             "projected", "interpenetration"])"
                                       : R"(["gravity", "contacts", "predictive", "projected"])";
    Simulation s(scene_from(R"({"steps": 20, "effects": )" + effects + ", " + rest));
    size_t points = 0, touching = 0, speculative = 0, predictive = 0;
    for (int i = 0; i < 20; ++i) {
      const sim::StepRecord& r = s.step();
      points += r.solver_points;
      touching += r.solver_points - r.speculative_points;
      speculative += r.speculative_points;
      predictive += r.predictive;
    }
    const sim::StageCounters& c = s.counters();
    EXPECT_EQ(c.gravity_forces, 20u);
    EXPECT_EQ(c.narrow_phase_batches, 20u);
    ASSERT_GT(touching, 0u) << "the box lands";
    ASSERT_GT(predictive, 0u) << "rays a speculative stage could use";
    if (listed) {
      EXPECT_EQ(c.friction_points, points) << "every point carries friction";
      EXPECT_EQ(c.restitution_points, touching) << "every touching point, and no speculative one, carries restitution";
      EXPECT_EQ(c.speculative_points, speculative);
      EXPECT_GT(c.speculative_points, 0u);
      EXPECT_EQ(c.interpenetration_passes, 4u);
    } else {
      EXPECT_EQ(speculative, 0u);
      EXPECT_EQ(c.friction_points + c.restitution_points + c.speculative_points + c.interpenetration_passes, 0u);
    }
  }
}

// Projected contacts push along the impacted triangle's normal: on a
// frictionless ground no other direction, so a tilted box landing on an
// edge keeps its centre of mass from moving sideways. Pushed along the
// rays instead (a box's corner rays point inward, diagonally), the landing
// kicks it sideways.
// The thesis' ray contacts (nearest_surface off) push along the ray unless
// projected; contacts measured to the nearest surface push straight out of
// the ground either way.
TEST(Sim, ProjectedContactsPushAlongTheNormalOnly) {
  for (const auto& [projected, nearest] : {std::pair{true, false}, std::pair{false, false}, std::pair{false, true}}) {
    SCOPED_TRACE(std::string(projected ? "projected" : "not projected") + (nearest ? ", nearest surface" : ""));
    const std::string effects = projected ? R"(["gravity", "contacts", "predictive", "projected"])"
                                          : R"(["gravity", "contacts", "predictive"])";
    // 30° about x: the lowest edge is 0.25 (cos 30° + sin 30°) = 0.342 below the centre.
    Simulation s(scene_from(R"({"time_step": 0.008333333333333333, "steps": 120, "effects": )" + effects +
                            R"(, "narrow_phase": {"nearest_surface": )" + (nearest ? "true" : "false") + R"(},
      "bodies": [{"box": [0.25, 0.25, 0.25], "mass": 1,
                  "pose": {"position": [0, 0, 0.4], "orientation": [0.96592582628906831, 0.25881904510252074, 0, 0]}}]})"));
    double sideways = 0;  // the largest horizontal speed seen
    size_t contacts = 0;
    for (int i = 0; i < 120; ++i) {
      contacts += s.step().contacts;
      const Eigen::Vector3d v = s.bodies()[0].linear_velocity;
      sideways = std::max(sideways, std::hypot(v.x(), v.y()));
    }
    ASSERT_GT(contacts, 0u);
    if (projected || nearest)
      EXPECT_LT(sideways, 1e-6);
    else
      EXPECT_GT(sideways, 1e-2);
  }
}

// The interpenetration pass measures what is there: a box held 0.05 deep in
// the ground (no gravity, no contacts to push it out) has four corners sunk
// 0.05, each reached by a diagonal ray 0.05 √3 long (the true penetration
// 0.05), on the pass's steps (every 5th and the last) and on no other;
// unlisted, no step measures.
TEST(Sim, InterpenetrationMeasuresTheDepthThere) {
  for (bool listed : {true, false}) {
    Simulation s(scene_from(std::string(R"({"steps": 12, "interpenetration": {"every": 5}, "effects": )") +
                            (listed ? R"(["interpenetration"])" : "[]") + R"(,
      "bodies": [{"box": [0.25, 0.25, 0.25], "pose": {"position": [0, 0, 0.2]}}]})"));
    for (int i = 0; i < 12; ++i) {
      const sim::StepRecord& r = s.step();
      const bool due = listed && ((i + 1) % 5 == 0 || i == 11);
      ASSERT_EQ(r.interpenetration >= 0, due) << "step " << i;
      if (!due) continue;
      EXPECT_NEAR(r.deepest, 0.05, 1e-5) << "step " << i;
      EXPECT_NEAR(r.interpenetration, 4 * 0.05 * std::sqrt(3.0), 1e-4) << "step " << i;
      EXPECT_NEAR(r.projected, 4 * 0.05, 1e-4) << "step " << i << ": each corner 0.05 along the ground's normal";
      EXPECT_NEAR(r.deepest_true, 0.05, 1e-5) << "step " << i << ": the true penetration, straight down";
      EXPECT_NEAR(r.true_penetration, 4 * 0.05, 1e-4) << "step " << i;
    }
    EXPECT_EQ(s.counters().interpenetration_passes, listed ? 3u : 0u);
  }
}

// The zoo (data/scenes/zoo.json: knot tubes, gears, cacti, coarse
// polyhedra, rings, blobs and primitives, its seed 1) piles up and holds:
// from 1.5 s on no body lies deeper in the ground than 1% of its size and
// no pair stays deeper than 2% of its smaller body for more than 30 steps;
// at the end the true penetration left is small and the pile at rest. With
// Bullet's own setup (one step, erp2 0.2) a body sank 3.8% and a pair
// stayed deep for 132 steps (docs/results/zoo/seeds: seeds 1 to 5).
TEST(Sim, ZooPileHolds) {
  Simulation s(sim::load_scene(std::string(RTCD_DATA_DIR) + "/scenes/zoo.json"), "embree");
  ASSERT_EQ(s.scene().seed, 1u);
  double ground = 0;
  uint64_t longest = 0, measured = 0;
  for (uint64_t i = 0; i < s.scene().steps; ++i) {
    const sim::StepRecord& r = s.step();
    if (r.time < 1.5 - 1e-9 || !(r.true_penetration >= 0.0)) continue;
    ++measured;
    ground = std::max(ground, r.ground_depth_fraction);
    longest = std::max(longest, r.longest_deep_run);
  }
  EXPECT_GT(measured, 60u);
  EXPECT_LE(ground, 0.01) << "deepest body in the ground, over its size";
  EXPECT_LE(longest, 30u) << "steps a pair stayed deeper than 2% of its smaller body";
  const sim::StepRecord& last = s.last();
  ASSERT_GE(last.true_penetration, 0.0) << "the last step is measured";
  EXPECT_LT(last.true_penetration, 5.0);
  EXPECT_LT(last.deepest_true, 0.05);
  EXPECT_LT(last.kinetic_energy, 50.0) << "at rest";
}

// Two gears (8 cm thick) pressed 5 cm into each other, the lower on the
// ground: past the lower's middle its nearest surface is its underside, so
// pushes to the nearest surface hold the upper in. Contacts that keep
// pushing the way the gears met once the pair is deeper than a quarter of
// their thickness part them within 20 steps.
TEST(Sim, GearsPressedPastHalfComeApart) {
  Simulation s(scene_from(R"({"time_step": 0.016666666666666666, "duration": 1.5,
    "effects": ["gravity", "contacts", "friction", "predictive", "speculative", "projected", "interpenetration"],
    "interpenetration": {"every": 1}, "ground": {"height": 0.0, "friction": 0.6},
    "solver": {"substeps": 4, "erp2": 0.8},
    "bodies": [
      {"name": "lower", "mesh": "../meshes/zoo/gear.obj", "density": 1000, "friction": 0.6, "pose": {"position": [0, 0, 0.04]}},
      {"name": "upper", "mesh": "../meshes/zoo/gear.obj", "density": 1000, "friction": 0.6,
       "pose": {"position": [0.01, 0, 0.07], "orientation": [0.9962, 0, 0, 0.0872]}}]})"));
  const double size = 2 * std::hypot(0.2231, 0.04);  // the gear's bounding diameter
  const sim::StepRecord& first = s.step();
  ASSERT_GT(first.deepest_true, 0.015) << "pressed in deep";
  uint64_t apart_from = UINT64_MAX;
  while (s.steps_done() < s.scene().steps) {
    const sim::StepRecord& r = s.step();
    const bool deep = r.deepest_true > 0.02 * size;
    if (!deep && apart_from == UINT64_MAX) apart_from = r.step;
    if (deep) apart_from = UINT64_MAX;
  }
  EXPECT_LE(apart_from, 20u) << "the step from which the gears stay apart";
  EXPECT_GT(s.counters().entry_pushes, 0u);
}

void expect_scene_error(const std::string& json, const std::string& key);

// Sub-steps run the narrow phase and the solver once each; a scene whose
// sub-steps would be too short for Bullet is refused by name.
TEST(Sim, SubstepsRunTheNarrowPhaseInEach) {
  for (const uint32_t substeps : {1u, 3u}) {
    Simulation s(scene_from(R"({"steps": 5, "effects": ["gravity", "contacts"], "solver": {"substeps": )" +
                            std::to_string(substeps) + R"(}, "bodies": [{"box": [0.25, 0.25, 0.25], "pose": {"position": [0, 0, 0.2]}}]})"));
    for (int i = 0; i < 5; ++i) s.step();
    EXPECT_EQ(s.counters().narrow_phase_batches, 5u * substeps);
  }
  expect_scene_error(R"({"effects": [], "time_step": 1e-6, "solver": {"substeps": 2}, "bodies": [{"box": [1, 1, 1]}]})",
                     "solver.substeps: makes sub-steps shorter than");
  expect_scene_error(R"({"effects": [], "solver": {"erp2": 0}, "bodies": [{"box": [1, 1, 1]}]})", "solver.erp2");
}

// Snapshots draw a contact as the solver sees it (its push): from each sunk corner
// 0.05 up the ground's normal, not along the 0.05 √3 diagonal ray that the
// full-ray drawing shows.
TEST(Sim, SnapshotsDrawTheSolversSegment) {
  Simulation s(scene_from(R"({"steps": 1, "effects": ["contacts", "projected"], "narrow_phase": {"nearest_surface": false},
    "bodies": [{"box": [0.25, 0.25, 0.25], "pose": {"position": [0, 0, 0.2]}}]})"));
  s.step();
  const std::span<const Contact> contacts = s.last_narrow_phase().contacts;
  ASSERT_EQ(contacts.size(), 4u);
  const auto segments = sim::contact_lines(contacts), rays = sim::contact_lines(contacts, true);
  ASSERT_EQ(segments.size(), 4u);
  for (size_t i = 0; i < 4; ++i) {
    EXPECT_LT((segments[i].from - contacts[i].origin).norm(), 1e-12);
    EXPECT_LT((segments[i].to - segments[i].from - Eigen::Vector3d(0, 0, 0.05)).norm(), 1e-5) << "contact " << i;
    EXPECT_NEAR((rays[i].to - rays[i].from).norm(), 0.05 * std::sqrt(3.0), 1e-5) << "contact " << i;
  }
  EXPECT_GT(s.snapshot(64, 48).rgb.size(), 0u);
}

// Speculative contacts stop nothing that is not approaching: a box gliding
// 0.02 above the ground and 0.02 past a static box's side (its corner rays
// meet them 0.035 away, inside the 0.05 extension) keeps its velocity, while
// the speculative points exist.
TEST(Sim, SpeculativeContactsMakeNoGhosts) {
  Simulation s(scene_from(R"({
    "time_step": 0.008333333333333333, "steps": 120,
    "effects": ["contacts", "friction", "predictive", "speculative", "projected"],
    "narrow_phase": {"distance_extension": 0.05, "displacement_threshold": 0.02},
    "bodies": [
      {"box": [0.25, 0.25, 0.25], "mass": 1, "velocity": [1.5, 0, 0], "pose": {"position": [-1, 0, 0.27]}},
      {"box": [0.25, 0.25, 0.25], "static": true, "pose": {"position": [0, 0.52, 0.27]}}
    ]
  })"));
  size_t speculative = 0;
  for (int i = 0; i < 120; ++i) {
    speculative += s.step().speculative_points;
    const auto b = s.bodies()[0];
    ASSERT_NEAR(b.linear_velocity.x(), 1.5, 1e-4) << "step " << i;
    ASSERT_NEAR(b.linear_velocity.norm(), 1.5, 1e-4) << "step " << i;
  }
  EXPECT_GT(speculative, 0u);
  EXPECT_EQ(s.counters().speculative_points, speculative);
}

// Speculative contacts do stop a body that approaches: a box falling fast
// onto the ground does not sink deeper than without them.
TEST(Sim, SpeculativeContactsCatchAnApproach) {
  double depth[2];
  for (bool speculative : {false, true}) {
    const std::string effects = speculative ? R"(["gravity", "contacts", "predictive", "speculative", "projected"])"
                                            : R"(["gravity", "contacts", "predictive", "projected"])";
    Simulation s(scene_from(R"({"time_step": 0.016666666666666666, "steps": 60, "effects": )" + effects + R"(,
      "narrow_phase": {"distance_extension": 0.2, "displacement_threshold": 0.05},
      "bodies": [{"box": [0.25, 0.25, 0.25], "mass": 1, "velocity": [0, 0, -6], "pose": {"position": [0, 0, 0.6]}}]})"));
    depth[speculative] = 0;
    for (int i = 0; i < 60; ++i) {
      s.step();
      depth[speculative] = std::max(depth[speculative], 0.25 - s.bodies()[0].pose.position.z());
    }
    if (speculative)
      EXPECT_GT(s.counters().speculative_points, 0u);
    else
      EXPECT_EQ(s.counters().speculative_points, 0u);
  }
  EXPECT_LT(depth[1], depth[0]);
  EXPECT_LT(depth[1], 0.01);
}

// Speculative points go first to the gaps that close within the step: in
// eight columns of two knot tubes (4.5 cm thick), each upper knot dropped
// 0.6 m onto the lower, no pair stays tube in tube. Spread over every
// predictive ray instead, the points went mostly to gaps far from where the
// tubes met: three pairs stayed tube in tube for 66 to 100 steps, two of
// them to the end.
TEST(Sim, SpeculativePointsGoWhereTheBodiesClose) {
  Simulation s(scene_from(R"({"time_step": 0.016666666666666666, "duration": 2.0, "seed": 7,
    "effects": ["gravity", "contacts", "friction", "predictive", "speculative", "projected", "interpenetration"],
    "interpenetration": {"every": 2}, "ground": {"height": 0.0, "friction": 0.6},
    "bodies": [{"name": "knot", "mesh": "../meshes/zoo/knot.obj", "count": 16, "density": 1000, "friction": 0.6,
      "grid": {"cells": [4, 2, 2], "origin": [-1.5, -0.5, 0.3], "spacing": [1.0, 1.0, 0.6], "jitter": 0.05,
               "random_orientation": true}}]})"));
  uint64_t longest = 0, measured = 0;
  while (s.steps_done() < s.scene().steps) {
    const sim::StepRecord& r = s.step();
    if (r.time < 1.0 || !(r.true_penetration >= 0.0)) continue;
    ++measured;
    longest = std::max(longest, r.longest_deep_run);
  }
  EXPECT_GT(measured, 20u);
  EXPECT_GT(s.counters().speculative_points, 0u);
  EXPECT_LE(longest, 30u) << "steps a pair stayed deeper than 2% of a knot's size";
}

void expect_scene_error(const std::string& json, const std::string& key) {
  try {
    scene_from(json);
    ADD_FAILURE() << "accepted: " << json;
  } catch (const sim::SceneError& e) {
    EXPECT_NE(std::string(e.what()).find(key), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("inline.json"), std::string::npos) << e.what();
  }
}

TEST(Sim, BadScenesNameTheKey) {
  const std::string body = R"("bodies": [{"box": [1, 1, 1]}])";
  expect_scene_error(R"({"effects": [], "colour": 1, )" + body + "}", "colour: unknown key");
  expect_scene_error(R"({"effects": [], "time_step": "fast", )" + body + "}", "time_step: must be a number");
  expect_scene_error(R"({"effects": [], "time_step": 0, )" + body + "}", "time_step");
  // Bullet would take no step at all (scene fuzzer).
  expect_scene_error(R"({"effects": [], "time_step": 1e-8, )" + body + "}", "time_step: is 1e-08, must be in [1e-06, 10]");
  expect_scene_error(R"({"effects": ["gravity", "wind"], )" + body + "}", "effects[1]: unknown effect \"wind\"");
  expect_scene_error(R"({"effects": ["friction"], )" + body + "}", "\"friction\" needs \"contacts\"");
  expect_scene_error(R"({"effects": ["contacts", "speculative"], )" + body + "}", "\"speculative\" needs \"predictive\"");
  expect_scene_error(R"({"effects": ["contacts", "predictive"], "narrow_phase": {"predictive": true}, )" + body + "}",
                     "narrow_phase.predictive: conflicts with effects");
  expect_scene_error(R"({"effects": [], "bodies": [{"box": [1, 1, 1], "mass": -2}]})", "bodies[0].mass");
  // Below the narrow phase's smallest body: the loader says so (scene fuzzer).
  expect_scene_error(R"({"effects": [], "bodies": [{"sphere": 1e-12}]})", "bodies[0].sphere: is below the smallest body");
  expect_scene_error(R"({"effects": [], "bodies": [{"box": [1e-12, 1e-12, 1e-12]}]})", "bodies[0].box: is below");
  expect_scene_error(R"({"effects": [], "bodies": [{"mesh": "../meshes/nowhere.obj"}]})",
                     "bodies[0].mesh: no such mesh file");
  expect_scene_error(R"({"effects": [], "bodies": [{"box": [1, 1, 1], "grid": {"cells": [2, 1]}}]})",
                     "bodies[0].grid.cells");
  expect_scene_error(R"({"effects": [], "bodies": [{"box": [1, 1, 1], "count": 3}]})", "bodies[0].count");
  expect_scene_error(R"({"bodies": []})", "effects: is required");
  expect_scene_error(R"({"effects": [], )", "not valid JSON");
  expect_scene_error(R"({"effects": [], "time_step": 1e400, )" + body + "}", "not valid JSON");  // found by fuzz/scene.cpp
}

// Same scene, seed and backend: the same final state bit for bit, with one
// thread or two, run after run; and listing `interpenetration` (its own
// narrow phase) changes nothing.
TEST(Sim, RunsAreBitIdenticalAcrossThreadsRepeatsAndMeasurement) {
  const auto run = [](int threads, bool measure) {
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, size_t(threads));
    const std::string effects = std::string(R"(["gravity", "contacts", "friction", "predictive", "projected")") +
                                (measure ? R"(, "interpenetration"])" : "]");
    Simulation s(scene_from(R"({"steps": 90, "seed": 7, "effects": )" + effects + R"(, "interpenetration": {"every": 3},
      "narrow_phase": {"distance_extension": 0.05, "displacement_threshold": 0.02},
      "bodies": [{"mesh": "../meshes/blob_902.obj", "scale": 0.25, "count": 12,
                  "grid": {"cells": [3, 2, 2], "origin": [0, 0, 0.4], "spacing": [0.55, 0.55, 0.55], "jitter": 0.05,
                           "random_orientation": true}}]})"));
    for (int i = 0; i < 90; ++i) s.step();
    return s.state_hash();
  };
  const uint64_t reference = run(1, false);
  EXPECT_EQ(run(2, false), reference);
  EXPECT_EQ(run(2, false), reference);
  EXPECT_EQ(run(1, true), reference);
}

// Generated blobs emitted over time appear at the rate asked, on the emitter's circle.
TEST(Sim, EmitterAddsBodiesAtItsRate) {
  Simulation s(scene_from(R"({"time_step": 0.01, "steps": 100, "effects": ["gravity", "contacts", "predictive"], "ground": false,
    "bodies": [{"blob": {"triangles": 200, "seed": 2, "radius": 0.1}, "count": 5,
                "emitter": {"rate": 10, "centre": [0, 0, 2], "radius": 1, "angular_speed": 5}}]})"));
  // Body k appears on the step whose start time reaches k / rate: 0, 10, 20, ...
  for (int i = 0; i < 25; ++i) s.step();
  EXPECT_EQ(s.bodies().size(), 3u);
  for (int i = 25; i < 100; ++i) s.step();
  const auto bodies = s.bodies();
  ASSERT_EQ(bodies.size(), 5u);
  for (size_t k = 0; k < bodies.size(); ++k) {
    // Emitted at angle 5 t, t = k / rate, on the circle of radius 1, then falling straight down.
    const double angle = 0.5 * double(k);
    EXPECT_NEAR(bodies[k].pose.position.x(), std::cos(angle), 1e-4) << k;
    EXPECT_NEAR(bodies[k].pose.position.y(), std::sin(angle), 1e-4) << k;
    EXPECT_LT(bodies[k].pose.position.z(), 2.0);
  }
  EXPECT_EQ(s.last().bodies, 5u);
}

}  // namespace
}  // namespace rtcd::test

namespace rtcd::test {
namespace {

int run_cli(const std::string& args) {
  const int status = std::system((std::string(RTCD_CLI) + " " + args + " > /dev/null 2>&1").c_str());
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

// `rtcd run` leaves the CSV, the JSON, the plots and the snapshots.
TEST(SimCli, RunLeavesItsOutputs) {
  const std::filesystem::path out = std::filesystem::temp_directory_path() / "rtcd_run_test";
  std::filesystem::remove_all(out);
  const std::string recording = (out / "run.rtcdrec").string();
  ASSERT_EQ(run_cli(std::string("run ") + RTCD_DATA_DIR + "/scenes/default.json --steps 12 --out " + out.string() +
                    " --record " + recording),
            0);
  for (const char* file : {"steps.csv", "summary.json", "time_per_step.png", "pairs_and_rays.png",
                           "interpenetration.png", "snapshot_0.png", "snapshot_11.png"})
    EXPECT_TRUE(std::filesystem::exists(out / file)) << file;
  std::ifstream csv(out / "steps.csv");
  size_t lines = 0;
  for (std::string line; std::getline(csv, line);) ++lines;
  EXPECT_EQ(lines, 13u) << "a header and a line per step";
  // --record: the steps run, as `rtcd replay` reads them.
  const sim::Recording r = sim::Recording::read(recording);
  EXPECT_EQ(r.steps().size(), 12u);
  EXPECT_EQ(r.kinds().size(), r.scene().body_count() + 1) << "the scene's bodies and the ground";
  EXPECT_EQ(run_cli("replay " + recording + " --mode full"), 0);
}

// A simulation that blows up stops naming the step and the body, exits 1
// and keeps what it wrote. (A mass of 1e-40 kg has an infinite inverse in
// Bullet's single precision: its first step is NaN.)
TEST(SimCli, BlowUpStopsNamingStepAndBody) {
  const std::string json = R"({"steps": 10, "effects": ["gravity", "contacts"],
    "bodies": [{"name": "feather", "box": [0.1, 0.1, 0.1], "mass": 1e-40, "pose": {"position": [0, 0, 1]}}]})";
  Simulation s(scene_from(json));
  try {
    s.step();
    ADD_FAILURE() << "no blow-up";
  } catch (const sim::SimulationError& e) {
    EXPECT_STREQ(e.what(), "step 0: body feather has a non-finite pose");
  }
  EXPECT_EQ(s.steps_done(), 0u);
  const std::filesystem::path dir = std::filesystem::temp_directory_path() / "rtcd_blow_up";
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  std::ofstream(dir / "scene.json") << json;
  EXPECT_EQ(run_cli("run " + (dir / "scene.json").string() + " --no-plots --out " + (dir / "run").string()), 1);
  EXPECT_TRUE(std::filesystem::exists(dir / "run" / "steps.csv"));
  std::ifstream summary(dir / "run" / "summary.json");
  const std::string text((std::istreambuf_iterator<char>(summary)), std::istreambuf_iterator<char>());
  EXPECT_NE(text.find("step 0: body feather has a non-finite pose"), std::string::npos);
}

// Every committed scene runs; bad scenes exit 2.
TEST(SimCli, CommittedScenesRunAndBadScenesExit2) {
  const std::filesystem::path out = std::filesystem::temp_directory_path() / "rtcd_scene_runs";
  for (const auto& entry : std::filesystem::directory_iterator(std::string(RTCD_DATA_DIR) + "/scenes")) {
    if (entry.path().extension() != ".json") continue;
    EXPECT_EQ(run_cli("run " + entry.path().string() + " --steps 3 --no-plots --out " + (out / entry.path().stem()).string()), 0)
        << entry.path();
  }
  const std::filesystem::path bad = std::filesystem::temp_directory_path() / "rtcd_bad_scene.json";
  std::ofstream(bad) << R"({"effects": ["gravity"], "time_step": 0, "bodies": []})";
  EXPECT_EQ(run_cli("run " + bad.string() + " --out /tmp/rtcd_bad_run"), 2);
  EXPECT_EQ(run_cli("run /nonexistent/scene.json"), 2);
}

}  // namespace
}  // namespace rtcd::test
