// Hard cases that must stay numerically stable, each a named test run on
// every usable backend: rays through shared edges and vertices, targets far
// from the origin, parallel rays, zero-area and sliver triangles, resting
// contact, one body inside the other, thin, tiny, huge and far bodies, a
// 100k-triangle target, open and non-manifold meshes, a concave trap,
// rotations near 0 and 180 degrees and q against -q, determinism of the whole
// output across thread counts and runs.
#include <cmath>
#include <random>

#include <gtest/gtest.h>
#include <tbb/global_control.h>
#include <tbb/task_arena.h>

#include "rtcd/backend.hpp"
#include "rtcd/error.hpp"
#include "rtcd/mesh_gen.hpp"
#include "rtcd/oracle/exact.hpp"
#include "rtcd/validation/differential.hpp"
#include "same_steps.hpp"
#include "support.hpp"

namespace rtcd::test {
namespace {

using Eigen::Vector3d;
using Eigen::Vector3f;
using validation::Family;
using validation::RunMode;

// An octahedron of half-diagonal s: its vertex normals are the axes.
Mesh octahedron(float s) {
  std::vector<Vector3f> p = {{s, 0, 0}, {-s, 0, 0}, {0, s, 0}, {0, -s, 0}, {0, 0, s}, {0, 0, -s}};
  std::vector<Mesh::Triangle> t = {{0, 2, 4}, {2, 1, 4}, {1, 3, 4}, {3, 0, 4},
                                   {2, 0, 5}, {1, 2, 5}, {3, 1, 5}, {0, 3, 5}};
  return Mesh(p, t);
}

Mesh scaled(const Mesh& m, double s) {
  std::vector<Vector3f> p;
  for (const auto& v : m.positions()) p.push_back((v.cast<double>() * s).cast<float>());
  return Mesh(p, {m.triangles().begin(), m.triangles().end()});
}

// 37,861 sources in all directions (a sampled sphere volume) wholly inside
// a closed target: every ray must come out a contact.
size_t misses_inside(const std::string& backend, std::shared_ptr<const Shape> target, const Pose& where,
                     double sphere_radius) {
  auto source = std::make_shared<Shape>(Sphere{sphere_radius}, 3000.0 / (sphere_radius * sphere_radius));
  PairRig rig(backend, source, std::move(target));
  Pose a = where;
  a.orientation = Eigen::Quaterniond(0.3, -0.2, 0.9, 0.1).normalized();
  const StepResult r = rig.step(a, where);
  size_t from_a = 0;
  for (const Contact& c : r.contacts) {
    from_a += c.source == Side::a;
    EXPECT_TRUE(std::isfinite(c.depth));
  }
  return source->sources().origins.size() - from_a;
}

// A family of two shapes for a differential run: every deep origin found,
// no false ray, depths exact.
void expect_exact(const std::string& backend, const Family& f, size_t pairs, RunMode mode = RunMode::full) {
  validation::RunOptions o;
  o.backend = backend;
  o.mode = mode;
  o.pairs = pairs;
  o.with_oracles = false;
  o.config.distance_extension = 0.1 * f.reach;
  o.config.displacement_threshold = f.iterative_threshold();
  const validation::RunResult r = validation::run_family(f, o);
  const validation::Summary& s = r.summary;
  EXPECT_GT(s.colliding, pairs / 5) << "too few colliding pairs: vacuous";
  EXPECT_EQ(s.missed, 0u) << "of " << s.deep;
  EXPECT_EQ(s.false_rays, 0u);
  EXPECT_LE(s.max_relative_depth_error, 1e-4);
  for (const auto& m : r.pairs)
    if (m.missed || m.false_rays || m.max_relative_depth_error > 1e-4) {
      ADD_FAILURE() << validation::describe(f, m, o);
      break;
    }
}

Family family(std::string name, Mesh a, Mesh b, double reach) {
  Family f;
  f.name = std::move(name);
  f.a = shape(std::move(a));
  f.b = shape(std::move(b));
  f.reach = reach;
  return f;
}

class Robustness : public ::testing::TestWithParam<std::string> {};

// Each inward ray of a small octahedron at the centre of a cube runs exactly
// through the middle of a face's diagonal, the edge two triangles share.
// Each of a small cube's runs exactly through a corner of the big one.
// Their depth along the ray (the thesis' contacts) is 1.1 or 1.1 sqrt(3);
// the nearest surface is 0.9 away.
TEST_P(Robustness, RaysThroughSharedEdgesAndVerticesAreFound) {
  for (const auto& [through_vertex, nearest] :
       {std::pair{false, false}, std::pair{true, false}, std::pair{false, true}, std::pair{true, true}}) {
    auto source = through_vertex ? shape(gen::box({0.1, 0.1, 0.1})) : shape(octahedron(0.1f));
    Config config;
    config.nearest_surface = nearest;
    PairRig rig(GetParam(), source, shape(gen::box({1, 1, 1})), config);
    for (int step = 0; step < 3; ++step) {  // full, then walks with no motion
      const StepResult r = rig.step(Pose{}, Pose{});
      size_t from_a = 0;
      for (const Contact& c : r.contacts) {
        if (c.source != Side::a) continue;
        ++from_a;
        EXPECT_NEAR(c.depth, nearest ? 0.9 : through_vertex ? 1.1 * std::sqrt(3.0) : 1.1, 1e-6);
      }
      EXPECT_EQ(from_a, source->sources().origins.size()) << "step " << step << (through_vertex ? " vertex" : " edge");
      if (step > 0) {
        EXPECT_EQ(r.pairs[0].mode, PairMode::iterative);
        // Never oscillating: each walk ends on its first or second triangle.
        EXPECT_LE(r.stats.walk_steps, 2 * r.stats.rays_iterative);
      }
    }
  }
}

TEST_P(Robustness, WatertightFarFromTheOrigin) {
  const Pose far = at(148376, 1234, -223423);
  EXPECT_EQ(misses_inside(GetParam(), shape(gen::icosphere(1.0, 3)), far, 0.6), 0u);
  EXPECT_EQ(misses_inside(GetParam(), shape(gen::concave_blob(902, 7, 1.0)), far, 0.25), 0u);
}

// Rays lying in the plane of a target face: finite results, the rays that
// do leave the target found.
TEST_P(Robustness, RayInThePlaneOfATriangle) {
  PairRig rig(GetParam(), shape(octahedron(0.2f)), shape(gen::box({1, 1, 1})));
  const StepResult r = rig.step(at(0, 1, 0), Pose{});  // vertices (±0.2, 1, 0), (0, 1, ±0.2) lie on y = 1
  bool below = false;
  for (const Contact& c : r.contacts) {
    EXPECT_TRUE(std::isfinite(c.depth) && c.depth >= 0);
    EXPECT_TRUE(c.normal.allFinite());
    below = below || (c.source == Side::a && c.vertex == 3);  // (0, 0.8, 0): inside, leaves through y = 1
  }
  EXPECT_TRUE(below);
}

TEST_P(Robustness, ZeroAreaAndSliverTrianglesInTheTarget) {
  MeshOptions keep;
  keep.allow_zero_area = true;
  const Mesh zero = cube_with_fan({1, 0, -1}, keep);  // the centre on the edge z = -1: one triangle of zero area
  EXPECT_EQ(zero.report().zero_area_triangles, 1u);
  EXPECT_THROW(cube_with_fan({1, 0, -1}, {}), MeshError);
  const Mesh sliver = cube_with_fan({1, 0, -1 + 1e-5f}, {});
  for (const Mesh* m : {&zero, &sliver}) EXPECT_EQ(misses_inside(GetParam(), shape(*m), Pose{}, 0.7), 0u);
}

// Coincident faces: vertices exactly on the other body's surface. With no
// motion the contacts do not flicker from one step to the next.
TEST_P(Robustness, RestingContactDoesNotFlicker) {
  PairRig rig(GetParam(), shape(gen::box({0.5, 0.5, 0.5})), shape(gen::concave_blob(902, 3, 1.0)));
  const Pose b = at(Vector3d(1.2, 0.1, 0.0), Eigen::Quaterniond(0.9, 0.1, 0.3, 0.2));
  const auto first = penetrating(rig.step(Pose{}, b));
  ASSERT_FALSE(first.empty());
  for (int step = 0; step < 5; ++step) EXPECT_EQ(penetrating(rig.step(Pose{}, b)), first) << "step " << step;

  PairRig cubes(GetParam(), shape(gen::box({0.5, 0.5, 0.5})), shape(gen::box({0.5, 0.5, 0.5})));
  const auto touching = penetrating(cubes.step(Pose{}, at(1, 0, 0)));
  for (int step = 0; step < 5; ++step) EXPECT_EQ(penetrating(cubes.step(Pose{}, at(1, 0, 0))), touching);
}

TEST_P(Robustness, OneBodyWhollyInsideTheOther) {
  auto small = shape(gen::concave_blob(902, 4, 0.15)), big = shape(gen::concave_blob(902, 5, 1.0));
  PairRig rig(GetParam(), small, big);
  const Pose a = at(Vector3d(0.05, -0.02, 0.03), Eigen::Quaterniond(0.7, 0.1, -0.5, 0.3));
  const StepResult r = rig.step(a, Pose{});
  const oracle::ExactShape exact(big);
  const auto truth = exact.rays_from(*small, a, Pose{}, 1e-6);
  for (const auto& t : truth) ASSERT_TRUE(t.deep()) << "the small body is not wholly inside";
  size_t from_a = 0;
  for (const Contact& c : r.contacts) {
    if (c.source != Side::a) continue;
    ++from_a;
    ASSERT_TRUE(truth[c.vertex].inside);
    EXPECT_NEAR(c.depth, truth[c.vertex].penetration, 1e-6) << "the true penetration";
  }
  EXPECT_EQ(from_a, small->sources().origins.size());
}

TEST_P(Robustness, PlateThinnerThanDistanceExtension) {
  Family f = family("thin plate", gen::concave_blob(902, 6, 0.6), gen::box({1, 1, 0.005}), 1.5);
  f.thinnest = 0.01;
  expect_exact(GetParam(), f, 300);
}

TEST_P(Robustness, TinyHugeAndFarBodies) {
  for (double s : {1e-4, 1e4}) {
    SCOPED_TRACE(s);
    Family f = family("scaled", scaled(gen::concave_blob(902, 8, 0.6), s), scaled(gen::torus(1, 0.35, 48, 24), s),
                      1.8 * s);
    expect_exact(GetParam(), f, 200);
  }
  Family far = family("far", gen::concave_blob(902, 8, 0.6), gen::concave_blob(902, 9, 1.0), 2.0);
  far.origin = {1e6, -1e6, 1e6};
  expect_exact(GetParam(), far, 200);
}

// The supported sizes (mesh.hpp, docs/ARCHITECTURE.md "Sizes"), at both
// edges. Coordinates up to 1e12: a unit box wholly inside a cube whose
// corners sit at 1e12 gets its 8 contacts with exact depths (1e12 - 0.5 to
// the nearest face), and a pair
// drawn around bodies reaching 0.95e12 is judged exact; beyond 1e12 a mesh is
// refused. Bodies as small as 1e-9 are judged exact too.
TEST_P(Robustness, SupportedCoordinateRangeEdges) {
  PairRig rig(GetParam(), shape(gen::box({0.5, 0.5, 0.5})), shape(gen::box({1e12, 1e12, 1e12})));
  const StepResult r = rig.step(Pose{}, Pose{});
  size_t corners = 0;
  for (const Contact& c : r.contacts) {
    if (c.source != Side::a) continue;
    ++corners;
    EXPECT_NEAR(c.depth / (1e12 - 0.5), 1.0, 1e-6);
  }
  EXPECT_EQ(corners, 8u);
  try {
    gen::box({2e12, 2e12, 2e12});
    ADD_FAILURE() << "a mesh beyond the supported coordinates was accepted";
  } catch (const MeshError& e) {
    EXPECT_EQ(e.kind(), MeshErrorKind::out_of_range);
    EXPECT_NE(std::string(e.what()).find("supported coordinate range"), std::string::npos) << e.what();
  }
  for (double s : {1e-9, 0.7e12}) {  // blob diagonal 2.1e-9; torus reaching 0.95e12
    SCOPED_TRACE(s);
    Family f = family("edge", scaled(gen::concave_blob(902, 8, 0.6), s), scaled(gen::torus(1, 0.35, 48, 24), s),
                      1.8 * s);
    expect_exact(GetParam(), f, 100);
  }
}

// Two bodies 1e4 apart in size (kMaxSizeRatio): the small one straddles the
// large one's surface. Every origin farther than 1e-6 of the large body's
// radius (1% of the small one's) from the surface is judged right.
TEST_P(Robustness, SupportedSizeRatioEdge) {
  auto small = shape(gen::concave_blob(902, 21, 0.6));
  auto large = shape(scaled(gen::concave_blob(902, 22, 1.0), 6000.0));
  ASSERT_NEAR(large->radius() / small->radius(), kMaxSizeRatio, 0.2 * kMaxSizeRatio);
  const oracle::ExactShape exact_large(large), exact_small(small);
  const double margin = 1e-6 * large->radius();
  PairRig rig(GetParam(), small, large);
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> u(-1, 1);
  const Mesh& surface = *large->mesh();
  size_t judged = 0, inside = 0;
  for (int i = 0; i < 40; ++i) {
    // Around the centre of a random triangle of the large body, within the small one's radius.
    const auto& t = surface.triangles()[size_t(rng() % surface.triangle_count())];
    const Vector3d centre = (surface.positions()[t[0]] + surface.positions()[t[1]] + surface.positions()[t[2]])
                                .cast<double>() / 3;
    const Vector3d normal = surface.triangle_normals()[size_t(&t - surface.triangles().data())].cast<double>();
    const Pose a = at(centre + 0.6 * u(rng) * normal + 0.2 * Vector3d(u(rng), u(rng), u(rng)),
                      Eigen::Quaterniond(u(rng), u(rng), u(rng), u(rng)).normalized());
    const StepResult r = rig.step(a, Pose{});
    std::set<uint32_t> from_small, from_large;
    for (const Contact& c : r.contacts) (c.source == Side::a ? from_small : from_large).insert(c.vertex);
    const auto truth_small = exact_large.rays_from(*small, a, Pose{}, margin);
    for (uint32_t v = 0; v < truth_small.size(); ++v) {
      if (truth_small[v].deep()) {
        ++inside;
        EXPECT_TRUE(from_small.count(v)) << "missed vertex " << v << " pose " << i;
      }
      if (truth_small[v].far_outside()) {
        EXPECT_FALSE(from_small.count(v)) << "false vertex " << v << " pose " << i;
      }
      judged += truth_small[v].deep() || truth_small[v].far_outside();
    }
    const auto truth_large = exact_small.rays_from(*large, Pose{}, a, 1e-6 * small->radius());
    for (uint32_t v : from_large) {
      EXPECT_FALSE(truth_large[v].far_outside()) << "false vertex " << v << " of B";
    }
  }
  EXPECT_GT(inside, 1000u);  // not vacuous: many origins are inside
  EXPECT_GT(judged, 0.9 * 40 * small->sources().origins.size());
}

TEST_P(Robustness, HighResolutionTarget) {
  Mesh big = gen::concave_blob(100'000, 10, 1.0);
  ASSERT_GE(big.triangle_count(), 100'000u);
  // Few pairs: the basic backend tests every ray against all 100k triangles.
  expect_exact(GetParam(), family("100k", gen::concave_blob(902, 11, 0.5), std::move(big), 1.6), 16);
}

// An open target makes no inside claim of its own, but rays that cross it
// from behind are still reported, with finite values; non-manifold input is
// a clear error.
TEST_P(Robustness, OpenAndNonManifoldMeshes) {
  PairRig rig(GetParam(), shape(gen::concave_blob(902, 12, 0.5)), shape(gen::open_sheet(16, 3.0, 0.1)));
  for (int step = 0; step < 3; ++step) {
    const StepResult r = rig.step(at(0, 0, 0.1 * step), Pose{});
    for (const Contact& c : r.contacts) EXPECT_TRUE(std::isfinite(c.depth) && c.depth >= 0);
  }
  std::vector<Vector3f> p = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}};
  try {
    Mesh({p.begin(), p.end()}, {{0, 1, 2}, {1, 0, 3}, {0, 1, 4}});  // edge (0, 1) in three triangles
    FAIL() << "a non-manifold edge was accepted";
  } catch (const MeshError& e) {
    EXPECT_EQ(e.kind(), MeshErrorKind::non_manifold_edge);
  }
}

// A walk across the U's concavity, from inside one arm over the opening into
// the other: it ends with an explicit status within its step limit, and a
// full step finds every corner of the box inside the far arm. (Over the
// opening the corners' rays meet the rim exactly on an edge between a wall
// and the cap, a tie each tracer may break its own way: not asserted.)
TEST_P(Robustness, ConcaveTrapForTheWalk) {
  Config c;
  c.mode = Mode::iterative;
  c.max_walk_steps = 4;
  PairRig rig(GetParam(), shape(gen::box({0.3, 0.3, 0.3})), shape(gen::u_shape(1.0)), c);
  rig.step(at(1.0, 0.5, 0), Pose{});
  for (int k = 1; k <= 20; ++k) {
    const StepResult r = rig.step(at(1.0 - 0.1 * k, 0.5, 0), Pose{});
    EXPECT_LE(r.stats.walk_steps, size_t(*c.max_walk_steps) * r.stats.rays_iterative);
  }
  Config full = c;
  full.mode = Mode::full;
  PairRig fresh(GetParam(), shape(gen::box({0.3, 0.3, 0.3})), shape(gen::u_shape(1.0)), full);
  const StepResult r = fresh.step(at(-1.0, 0.5, 0), Pose{});
  size_t from_box = 0;
  for (const Contact& contact : r.contacts) from_box += contact.source == Side::a;
  EXPECT_EQ(from_box, 8u);
}

// Equation 2.1 through the narrow phase, at a rotation near zero and one
// near a half turn: a pair turned further by a tiny angle stays iterative,
// and q and -q (the same rotation) give the same step.
TEST_P(Robustness, RotationsNearZeroAndHalfTurnAndNegatedQuaternion) {
  auto a = shape(gen::concave_blob(902, 13, 0.6)), b = shape(gen::concave_blob(902, 14, 1.0));
  const Vector3d axis = Vector3d(0.3, 0.4, 0.5).normalized(), position(1.1, 0.2, 0);
  for (double angle : {1e-7, M_PI - 1e-7}) {
    SCOPED_TRACE("angle " + std::to_string(angle));
    const Eigen::Quaterniond q(Eigen::AngleAxisd(angle, axis)), turned(Eigen::AngleAxisd(angle + 1e-7, axis));
    const auto negated = [](const Eigen::Quaterniond& r) { return Eigen::Quaterniond(-r.coeffs()); };
    PairRig plus(GetParam(), a, b), minus(GetParam(), a, b);
    const StepResult x = plus.step(at(position, q), Pose{}), y = minus.step(at(position, negated(q)), Pose{});
    ASSERT_GT(x.contacts.size(), 10u) << "the bodies must overlap for the comparison to mean anything";
    EXPECT_EQ(penetrating(x), penetrating(y));
    ASSERT_EQ(x.contacts.size(), y.contacts.size());
    for (size_t k = 0; k < x.contacts.size(); ++k) EXPECT_NEAR(x.contacts[k].depth, y.contacts[k].depth, 1e-9);
    // Turned by a further 1e-7 rad, as q and as -q: far below the
    // displacement threshold, so both walk, to the same contacts.
    const StepResult xt = plus.step(at(position, turned), Pose{});
    const StepResult yt = minus.step(at(position, negated(turned)), Pose{});
    EXPECT_EQ(xt.pairs[0].mode, PairMode::iterative);
    EXPECT_EQ(yt.pairs[0].mode, PairMode::iterative);
    EXPECT_GT(xt.contacts.size(), 10u);
    EXPECT_EQ(penetrating(xt), penetrating(yt));
    EXPECT_EQ(penetrating(xt), penetrating(x)) << "a turn of 1e-7 rad moves no vertex in or out";
  }
}

// The backend's whole output bit for bit — every contact's ids, depth and
// normal, predictive rays, pair summaries and statistics, where the rays
// ran — across 1, 2 and 8 threads and a repeated run, over a sequence of
// steps in every mode: a scene of 1,100 pairs (past the pipeline's
// threshold for preparing and filling pairs on several threads) and one of
// concave pairs with many rays each.
TEST_P(Robustness, DeterministicAcrossRunsAndThreadCounts) {
  tbb::global_control allow(tbb::global_control::max_allowed_parallelism, 8);
  const auto run = [&](const Scene& scene, int threads) {
    tbb::task_arena arena(threads);
    std::vector<StepResult> steps;
    arena.execute([&] { steps = run_scene(GetParam(), scene); });
    return steps;
  };
  for (Mode mode : {Mode::full, Mode::iterative, Mode::automatic}) {
    for (const Scene& scene : {Scene{"plates", mode, 1100, 4}, Scene{"concave", mode, 48, 4}}) {
      SCOPED_TRACE(scene.family + " " + (mode == Mode::automatic ? "automatic" : to_string(mode)));
      const auto one = run(scene, 1);
      size_t reported = 0, walked = 0;
      for (const StepResult& s : one) {
        reported += s.contacts.size();
        walked += s.stats.rays_iterative;
      }
      EXPECT_GT(reported, 100u) << "too few contacts for the comparison to mean anything";
      if (mode != Mode::full) {
        EXPECT_GT(walked, 0u) << "no step walked";
      }
      for (const auto& [threads, label] : {std::pair{2, "2 threads"}, {8, "8 threads"}, {8, "8 threads again"}}) {
        SCOPED_TRACE(label);
        const auto other = run(scene, threads);
        expect_same_run(one, other);
        for (size_t s = 0; s < std::min(one.size(), other.size()); ++s)
          expect_same_placement(one[s].stats, other[s].stats, "step " + std::to_string(s));
      }
    }
  }
}

// Embree picks its instruction set at run time; pinned (`embree:isa=NAME`),
// every set this CPU runs gives the same output bit for bit: contacts,
// predictive rays, pair summaries and ray counts. Only the walk-step count
// may differ: a traced ray that lands on an edge two triangles share can be
// given either triangle, and the next step's walk from it reaches the same
// hit in a step more or fewer (measured: 1 or 2 in 7,000 to 16,000). At
// least two sets must be here to compare (every x86-64 CPU of the last
// decade runs sse2 and sse4.2).
TEST(Robustness, EmbreeInstructionSetsAgreeBitForBit) {
  std::vector<std::string> isas;
  for (const char* isa : {"sse2", "sse4.2", "avx", "avx2", "avx512"}) {
    try {
      make_narrow_phase(std::string("embree:isa=") + isa);
      isas.push_back(isa);
    } catch (const BackendError& e) {
      EXPECT_NE(std::string(e.what()).find("does not run"), std::string::npos) << e.what();
    }
  }
  ASSERT_GE(isas.size(), 2u) << "this CPU runs one instruction set: nothing to compare";
  for (Mode mode : {Mode::full, Mode::iterative, Mode::automatic}) {
    for (const Scene& scene : {Scene{"plates", mode, 200, 4}, Scene{"concave", mode, 32, 4}, Scene{"torus", mode, 32, 4}}) {
      SCOPED_TRACE(scene.family + " " + (mode == Mode::automatic ? "automatic" : to_string(mode)));
      const auto first = run_scene("embree:isa=" + isas[0], scene);
      for (size_t i = 1; i < isas.size(); ++i) {
        SCOPED_TRACE(isas[0] + " against " + isas[i]);
        auto other = run_scene("embree:isa=" + isas[i], scene);
        for (size_t k = 0; k < std::min(first.size(), other.size()); ++k) {
          const double a = double(first[k].stats.walk_steps), b = double(other[k].stats.walk_steps);
          EXPECT_LE(std::abs(a - b), 1e-3 * a) << "walk steps, step " << k;
          other[k].stats.walk_steps = first[k].stats.walk_steps;
        }
        EXPECT_GT(expect_same_run(first, other), 50u);
      }
    }
  }
}

INSTANTIATE_TEST_SUITE_P(Backends, Robustness, ::testing::ValuesIn(usable_backends()),
                         [](const auto& info) { return test_name(info.param); });

}  // namespace
}  // namespace rtcd::test
