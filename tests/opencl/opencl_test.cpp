// The OpenCL backend on PoCL's two CPU devices (POCL_DEVICES="pthread
// pthread", set by ctest): the brute-force variant equals `basic` bit for
// bit, the BVH variant finds what the exact reference finds, several
// devices equal one, and every fault ends in the same output as a run
// without it. These tests fail, never skip, when no OpenCL device exists.
#include <cstdlib>
#include <functional>

#include <gtest/gtest.h>

#include <random>
#include <set>

#include "opencl/bvh.hpp"
#include "opencl/opencl_backend.hpp"
#include "rtcd/mesh_gen.hpp"
#include "rtcd/error.hpp"
#include "rtcd/validation/differential.hpp"
#include "rtcd/validation/families.hpp"
#include "support.hpp"

namespace rtcd::test {
namespace {

using validation::Family;

// Pairs of a family stepped together, B moving a little each step: every
// step is one batch of many jobs, spread over the devices.
struct Scene {
  std::string family;
  Mode mode;
  size_t pairs = 16;
  size_t steps = 4;
  uint64_t seed = 7;
};

std::vector<StepResult> run_scene(const std::string& backend, const Scene& s) {
  const Family f = validation::make_family(s.family);
  Config config;
  config.mode = s.mode;
  auto narrow = make_narrow_phase(backend, config);
  const ShapeId sa = narrow->add_shape(f.a), sb = narrow->add_shape(f.b);
  std::vector<BodyPair> pairs;
  std::vector<validation::PosePair> poses;
  for (size_t i = 0; i < s.pairs; ++i) {
    poses.push_back(validation::random_poses(f, s.seed, i));
    pairs.push_back({narrow->add_body(sa, poses[i].a), narrow->add_body(sb, poses[i].b)});
  }
  std::vector<StepResult> results;
  for (size_t step = 0; step < s.steps; ++step) {
    for (size_t i = 0; i < s.pairs; ++i) {
      if (step > 0) poses[i] = validation::moved(f, poses[i], f.step_motion(), s.seed, step * s.pairs + i);
      narrow->set_pose(pairs[i].a, poses[i].a);
      narrow->set_pose(pairs[i].b, poses[i].b);
    }
    results.push_back(narrow->detect(pairs));
  }
  return results;
}

void expect_same_record(const RayRecord& x, const RayRecord& y) {
  EXPECT_EQ(x.source, y.source);
  EXPECT_EQ(x.source_body, y.source_body);
  EXPECT_EQ(x.target_body, y.target_body);
  EXPECT_EQ(x.vertex, y.vertex);
  EXPECT_EQ(x.triangle, y.triangle) << "vertex " << x.vertex;
  EXPECT_EQ(x.origin, y.origin);
  EXPECT_EQ(x.direction, y.direction);
  EXPECT_EQ(x.normal, y.normal);
}

// Everything a step reports, bit for bit, but the clock readings.
void expect_same_step(const StepResult& x, const StepResult& y, const std::string& where) {
  SCOPED_TRACE(where);
  ASSERT_EQ(x.pairs.size(), y.pairs.size());
  for (size_t i = 0; i < x.pairs.size(); ++i) {
    EXPECT_EQ(x.pairs[i].colliding, y.pairs[i].colliding) << "pair " << i;
    EXPECT_EQ(x.pairs[i].mode, y.pairs[i].mode) << "pair " << i;
    EXPECT_EQ(x.pairs[i].max_depth, y.pairs[i].max_depth) << "pair " << i;
    EXPECT_EQ(x.pairs[i].contact_count, y.pairs[i].contact_count) << "pair " << i;
    EXPECT_EQ(x.pairs[i].predictive_count, y.pairs[i].predictive_count) << "pair " << i;
  }
  ASSERT_EQ(x.contacts.size(), y.contacts.size());
  for (size_t k = 0; k < x.contacts.size(); ++k) {
    expect_same_record(x.contacts[k], y.contacts[k]);
    EXPECT_EQ(x.contacts[k].depth, y.contacts[k].depth);
    EXPECT_EQ(x.contacts[k].projected_depth, y.contacts[k].projected_depth);
    EXPECT_EQ(x.contacts[k].push, y.contacts[k].push);
  }
  ASSERT_EQ(x.predictive.size(), y.predictive.size());
  for (size_t k = 0; k < x.predictive.size(); ++k) {
    expect_same_record(x.predictive[k], y.predictive[k]);
    EXPECT_EQ(x.predictive[k].distance, y.predictive[k].distance);
  }
  const StepStats &a = x.stats, &b = y.stats;
  EXPECT_EQ(a.pairs_full, b.pairs_full);
  EXPECT_EQ(a.pairs_iterative, b.pairs_iterative);
  EXPECT_EQ(a.fallbacks_to_full, b.fallbacks_to_full);
  EXPECT_EQ(a.candidates, b.candidates);
  EXPECT_EQ(a.rays_full, b.rays_full);
  EXPECT_EQ(a.rays_predictive, b.rays_predictive);
  EXPECT_EQ(a.rays_iterative, b.rays_iterative);
  EXPECT_EQ(a.walk_steps, b.walk_steps);
  EXPECT_EQ(a.nearest_queries, b.nearest_queries);
  EXPECT_EQ(a.rays_retraced, b.rays_retraced);
  EXPECT_EQ(a.rays_watched, b.rays_watched);
  EXPECT_EQ(a.walk_endings, b.walk_endings);
}

size_t expect_same_run(const std::vector<StepResult>& x, const std::vector<StepResult>& y) {
  EXPECT_EQ(x.size(), y.size());
  size_t reported = 0;
  for (size_t s = 0; s < std::min(x.size(), y.size()); ++s) {
    expect_same_step(x[s], y[s], "step " + std::to_string(s));
    reported += y[s].contacts.size() + y[s].predictive.size();
  }
  return reported;
}

std::string mode_name(Mode m) { return m == Mode::automatic ? "auto" : to_string(m); }

TEST(OpenCl, PoclGivesTwoUsableDevices) {
  bool listed = false;
  for (const BackendInfo& b : available_backends())
    if (b.name == "opencl" || b.name == "opencl-basic") {
      listed = true;
      EXPECT_TRUE(b.usable) << b.name << ": " << b.detail;
      EXPECT_NE(b.detail.find("compute units"), std::string::npos) << b.detail;
      EXPECT_NE(b.detail.find("MiB"), std::string::npos) << b.detail;
    }
  ASSERT_TRUE(listed) << "the OpenCL backend is not built in";
  auto narrow = make_narrow_phase("opencl");
  EXPECT_EQ(narrow->name(), "opencl");
  ASSERT_EQ(narrow->devices().size(), 2u) << "ctest sets POCL_DEVICES=\"pthread pthread\"";
  for (const std::string& d : narrow->devices()) EXPECT_NE(d.find("BVH"), std::string::npos) << d;
  EXPECT_EQ(make_narrow_phase("opencl-basic:devices=1")->devices().size(), 1u);
  EXPECT_EQ(make_narrow_phase("opencl:cpu:devices=0,1")->devices().size(), 2u);
}

TEST(OpenCl, BadNamesAreBackendErrors) {
  EXPECT_THROW(make_narrow_phase("opencl:devices=7"), BackendError);
  EXPECT_THROW(make_narrow_phase("opencl:devices=0,0"), BackendError);
  EXPECT_THROW(make_narrow_phase("opencl:devices="), BackendError);
  EXPECT_THROW(make_narrow_phase("opencl:fast"), BackendError);
  EXPECT_THROW(make_narrow_phase("opencl:layout=padded"), BackendError);
  EXPECT_THROW(make_narrow_phase("openclx"), BackendError);
  bool embree = false;
  for (const BackendInfo& b : available_backends()) embree = embree || (b.name == "embree" && b.usable);
  EXPECT_EQ(make_narrow_phase("auto")->name(), embree ? "embree" : "opencl") << "auto keeps its fixed order";
}

// The brute-force variant against the CPU's basic backend: the same
// contacts, predictive rays, pair summaries and statistics, in every mode.
class BasicVariant : public ::testing::TestWithParam<std::tuple<std::string, Mode>> {};

TEST_P(BasicVariant, EqualsBasicBitForBit) {
  const auto& [family, mode] = GetParam();
  const Scene scene{family, mode};
  const size_t reported = expect_same_run(run_scene("opencl-basic", scene), run_scene("basic", scene));
  EXPECT_GT(reported, 0u) << "nothing reported: the comparison would be vacuous";
}

// The BVH prunes only boxes that cannot hold a nearer hit and breaks ties
// by triangle id like the brute force: it answers as `basic` does too.
class BvhVariant : public ::testing::TestWithParam<std::tuple<std::string, Mode>> {};

TEST_P(BvhVariant, EqualsBasicBitForBit) {
  const auto& [family, mode] = GetParam();
  const Scene scene{family, mode};
  const size_t reported = expect_same_run(run_scene("opencl", scene), run_scene("basic", scene));
  EXPECT_GT(reported, 0u);
}

const auto kFamilies = ::testing::Values("convex", "concave", "torus", "plates", "primitives");
const auto kModes = ::testing::Values(Mode::full, Mode::iterative, Mode::automatic);
std::string case_name(const ::testing::TestParamInfo<std::tuple<std::string, Mode>>& info) {
  return std::get<0>(info.param) + "_" + mode_name(std::get<1>(info.param));
}
INSTANTIATE_TEST_SUITE_P(Families, BasicVariant, ::testing::Combine(kFamilies, kModes), case_name);
INSTANTIATE_TEST_SUITE_P(Families, BvhVariant, ::testing::Combine(kFamilies, kModes), case_name);

// The device's BVH traversal is plain C: checked on the host against the
// brute force, ray by ray and point by point, with the tree's shape.
TEST(Bvh, AnswersAsTheBruteForce) {
  std::mt19937 g(5);
  std::uniform_real_distribution<float> u(-1.2f, 1.2f);
  for (const Mesh& mesh : {gen::concave_blob(902, 3), gen::torus(1.0, 0.3, 24, 12), gen::icosphere(1.0, 3)}) {
    const FlatBvh bvh = build_flat_bvh(mesh);
    std::vector<int> seen(mesh.triangle_count(), 0);
    for (rtcd_uint t : bvh.primitives) ++seen[t];
    EXPECT_EQ(std::count(seen.begin(), seen.end(), 1), long(mesh.triangle_count())) << "each triangle in one leaf";
    ASSERT_FALSE(bvh.nodes.empty());
    EXPECT_EQ(bvh.nodes[0].escape, bvh.nodes.size());
    const auto* positions = reinterpret_cast<const rtcd_vec3*>(mesh.positions().data());
    const auto* triangles = reinterpret_cast<const rtcd_uint*>(mesh.triangles().data());
    const rtcd_uchar* zero_area = mesh.zero_area().data();
    const auto n = rtcd_uint(mesh.triangle_count());
    size_t hits = 0;
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
      ASSERT_EQ(rtcd_bvh_nearest(origin, radius, bvh.nodes.data(), rtcd_uint(bvh.nodes.size()), bvh.primitives.data(),
                                 positions, triangles, zero_area),
                rtcd_brute_nearest(origin, radius, positions, triangles, zero_area, n))
          << "point " << i;
    }
    EXPECT_GT(hits, 500u) << "too few hits: the comparison would be vacuous";
  }
}

// Against the exact reference, on the 20,000-triangle family as well.
TEST(OpenCl, BvhMissesNothingInFullMode) {
  for (const std::string family : {"concave", "highres"}) {
    validation::RunOptions o;
    o.backend = "opencl";
    o.mode = validation::RunMode::full;
    o.pairs = 200;
    o.with_oracles = false;
    const validation::RunResult r = validation::run_family(validation::make_family(family), o);
    EXPECT_GT(r.summary.deep, 1000u) << family;
    EXPECT_EQ(r.summary.missed, 0u) << family << ": of " << r.summary.deep << " deep origins";
    EXPECT_EQ(r.summary.false_rays, 0u) << family;
    EXPECT_LE(r.summary.max_relative_depth_error, 1e-5) << family;
  }
}

// Jobs spread over two devices come back in job order: the same step as on one.
TEST(OpenCl, TwoDevicesEqualOne) {
  for (Mode mode : {Mode::full, Mode::automatic}) {
    const Scene scene{"concave", mode, 24, 4};
    const size_t reported = expect_same_run(run_scene("opencl", scene), run_scene("opencl:devices=1", scene));
    EXPECT_GT(reported, 0u);
  }
}

// A walking pair stays on the device that traced it and its tracked rays
// stay there: an iterative step sends the same bytes (the jobs and their
// poses) whatever number of rays it walks.
TEST(OpenCl, TrackedRaysStayOnTheirDevice) {
  for (const std::string backend : {"opencl", "opencl:devices=1"}) {
    SCOPED_TRACE(backend);
    const auto steps = run_scene(backend, {"concave", Mode::iterative, 16, 6});
    std::set<size_t> walked;
    for (size_t s = 1; s < steps.size(); ++s) {
      EXPECT_EQ(steps[s].stats.pairs_iterative, 16u);
      EXPECT_EQ(steps[s].stats.bytes_to_device, steps[1].stats.bytes_to_device) << "step " << s;
      EXPECT_GT(steps[s].stats.bytes_from_device, 0u);
      walked.insert(steps[s].stats.rays_iterative);
    }
    EXPECT_GT(walked.size(), 1u) << "every step walked as many rays: the test shows nothing";
  }
}

// Both layouts (by default grid for iterative batches, compacted for full
// ones) trace the same rays in the same order, on BVH and brute force.
TEST(OpenCl, LayoutsAgree) {
  for (Mode mode : {Mode::full, Mode::automatic}) {
    const Scene scene{"concave", mode, 24, 4};
    const auto by_mode = run_scene("opencl", scene);
    EXPECT_GT(expect_same_run(run_scene("opencl:layout=grid", scene), by_mode), 0u);
    EXPECT_GT(expect_same_run(run_scene("opencl:layout=compact", scene), by_mode), 0u);
  }
  for (Mode mode : {Mode::full, Mode::iterative}) {
    const Scene scene{"primitives", mode, 24, 4};
    EXPECT_GT(expect_same_run(run_scene("opencl-basic:layout=grid:devices=0", scene), run_scene("basic", scene)), 0u);
  }
}

// A device without fp64 has its rays placed by the host, with the same
// rtcd_place_ray: the same answers.
TEST(OpenCl, HostPlacementEqualsDevicePlacement) {
  ASSERT_EQ(setenv("RTCD_OPENCL_NO_FP64", "1", 1), 0);
  const auto narrow = make_narrow_phase("opencl-basic");
  const Scene scene{"concave", Mode::automatic};
  const auto placed_by_host = run_scene("opencl-basic", scene);
  ASSERT_EQ(unsetenv("RTCD_OPENCL_NO_FP64"), 0);
  ASSERT_FALSE(narrow->devices().empty());
  EXPECT_NE(narrow->devices()[0].find("placed in double on the host"), std::string::npos) << narrow->devices()[0];
  EXPECT_GT(expect_same_run(placed_by_host, run_scene("basic", scene)), 0u);
}

// Each fault, forced: one message naming it on stderr, and the same output
// as a run without it (the step and those after finished on the CPU).
class Faults : public ::testing::TestWithParam<std::tuple<OpenClFault, std::string>> {
 protected:
  void TearDown() override { inject_opencl_fault(OpenClFault::none); }
};

TEST_P(Faults, FinishOnTheCpuWithTheSameOutput) {
  const auto& [fault, reason] = GetParam();
  const Scene scene{"concave", Mode::automatic, 8, 4};
  const auto reference = run_scene("basic", scene);
  inject_opencl_fault(fault);
  ::testing::internal::CaptureStderr();
  const auto faulted = run_scene("opencl-basic", scene);
  const std::string err = ::testing::internal::GetCapturedStderr();
  inject_opencl_fault(OpenClFault::none);
  // The driver may print its own diagnostics (PoCL's compiler does).
  const size_t first = err.find("rtcd: opencl-basic: ");
  EXPECT_NE(first, std::string::npos) << err;
  EXPECT_EQ(err.find("rtcd: ", first + 1), std::string::npos) << "one message, on the first occurrence:\n" << err;
  EXPECT_NE(err.find(reason), std::string::npos) << err;
  EXPECT_NE(err.find("on the CPU (basic)"), std::string::npos) << err;
  EXPECT_GT(expect_same_run(faulted, reference), 0u);
}

std::string fault_name(const ::testing::TestParamInfo<Faults::ParamType>& info) {
  const char* names[] = {"none", "no_platform", "build", "out_of_memory", "mid_step"};
  return names[int(std::get<0>(info.param))];
}

INSTANTIATE_TEST_SUITE_P(
    Kinds, Faults,
    ::testing::Values(std::make_tuple(OpenClFault::no_platform, std::string("no OpenCL platform")),
                      std::make_tuple(OpenClFault::build, std::string("failed to build")),
                      std::make_tuple(OpenClFault::out_of_memory, std::string("CL_MEM_OBJECT_ALLOCATION_FAILURE")),
                      std::make_tuple(OpenClFault::mid_step, std::string("during a step"))),
    fault_name);

// The BVH variant falls back to the fastest CPU tracer and still answers.
TEST(OpenCl, BvhFaultFallsBackToEmbree) {
  inject_opencl_fault(OpenClFault::mid_step);
  ::testing::internal::CaptureStderr();
  const Scene scene{"convex", Mode::full, 8, 3};
  const auto faulted = run_scene("opencl", scene);
  const std::string err = ::testing::internal::GetCapturedStderr();
  inject_opencl_fault(OpenClFault::none);
  EXPECT_NE(err.find("on the CPU (embree)"), std::string::npos) << err;
  const auto reference = run_scene("embree", scene);
  ASSERT_EQ(faulted.size(), reference.size());
  // Full steps of convex pairs have no ties to break: the same contacts.
  for (size_t s = 0; s < faulted.size(); ++s) EXPECT_EQ(penetrating(faulted[s]), penetrating(reference[s])) << s;
}

}  // namespace
}  // namespace rtcd::test
