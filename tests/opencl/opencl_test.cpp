// The OpenCL backend on PoCL's two CPU devices (POCL_DEVICES="pthread
// pthread", set by ctest): the brute-force variant equals `basic` bit for
// bit, the BVH variant finds what the exact reference finds, several
// devices equal one, and every fault ends in the same output as a run
// without it. These tests fail, never skip, when no OpenCL device exists.
#include <chrono>
#include <cstdlib>
#include <functional>

#include <gtest/gtest.h>

#include <random>
#include <set>

#include "bvh_answers.hpp"
#include "opencl/opencl_backend.hpp"
#include "rtcd/backend.hpp"
#include "rtcd/mesh_gen.hpp"
#include "rtcd/error.hpp"
#include "rtcd/validation/differential.hpp"
#include "rtcd/validation/families.hpp"
#include "same_steps.hpp"
#include "support.hpp"

namespace rtcd::test {
namespace {

using validation::Family;

// The device did the work, not the CPU fallback (whose answers are the same
// by design, so equal output alone cannot tell): no step fell back, every
// candidate ray and edge ran on a device, and each of the `devices` ran some.
void expect_ran_on_devices(const std::vector<StepResult>& run, size_t devices) {
  std::vector<size_t> rays(devices, 0);
  for (size_t s = 0; s < run.size(); ++s) {
    const StepStats& stats = run[s].stats;
    EXPECT_EQ(stats.cpu_fallback, "") << "step " << s;
    ASSERT_EQ(stats.devices.size(), devices) << "step " << s;
    size_t sum = 0;
    for (size_t d = 0; d < devices; ++d) {
      rays[d] += stats.devices[d].rays;
      sum += stats.devices[d].rays;
    }
    EXPECT_EQ(sum, stats.candidates + stats.edges_tested) << "step " << s << ": rays the devices did not run";
    EXPECT_GT(stats.bytes_from_device, 0u) << "step " << s;
  }
  for (size_t d = 0; d < devices; ++d) EXPECT_GT(rays[d], 0u) << "device " << d << " ran no ray";
  // The first step has no pair state: its jobs are spread over every device.
  if (!run.empty()) {
    for (size_t d = 0; d < devices; ++d) EXPECT_GT(run[0].stats.devices[d].jobs, 0u) << "device " << d;
  }
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
  const auto device = run_scene("opencl-basic", scene);
  expect_ran_on_devices(device, 2);
  const size_t reported = expect_same_run(device, run_scene("basic", scene));
  EXPECT_GT(reported, 0u) << "nothing reported: the comparison would be vacuous";
}

// The BVH prunes only boxes that cannot hold a nearer hit and breaks ties
// by triangle id like the brute force: it answers as `basic` does too.
class BvhVariant : public ::testing::TestWithParam<std::tuple<std::string, Mode>> {};

TEST_P(BvhVariant, EqualsBasicBitForBit) {
  const auto& [family, mode] = GetParam();
  const Scene scene{family, mode};
  const auto device = run_scene("opencl", scene);
  expect_ran_on_devices(device, 2);
  const size_t reported = expect_same_run(device, run_scene("basic", scene));
  EXPECT_GT(reported, 0u);
}

const auto kFamilies = ::testing::Values("convex", "concave", "torus", "plates", "primitives");
const auto kModes = ::testing::Values(Mode::full, Mode::iterative, Mode::automatic);
std::string case_name(const ::testing::TestParamInfo<std::tuple<std::string, Mode>>& info) {
  return std::get<0>(info.param) + "_" + mode_name(std::get<1>(info.param));
}
INSTANTIATE_TEST_SUITE_P(Families, BasicVariant, ::testing::Combine(kFamilies, kModes), case_name);
INSTANTIATE_TEST_SUITE_P(Families, BvhVariant, ::testing::Combine(kFamilies, kModes), case_name);

// The edge and depth knobs, each turned from its default: both OpenCL kinds
// still step as `basic` does (one side's edges, rested and held edges, the
// thesis' ray contact), and the knob changed the run (else the case would
// repeat the default one).
class KnobVariant : public ::testing::TestWithParam<std::string> {};

TEST_P(KnobVariant, EqualsBasicBitForBit) {
  const std::string& knob = GetParam();
  Scene scene{"concave", Mode::automatic, 16, 8};
  Config& c = scene.config;
  if (knob == "edge_contacts") c.edge_contacts = false;
  if (knob == "edges_both_sides") c.edges_both_sides = false;
  if (knob == "edges_beside_contacts") c.edges_beside_contacts = false;
  if (knob == "edge_retest_motion") c.edge_retest_motion = 4.0 * validation::make_family("concave").step_motion();
  if (knob == "nearest_surface") c.nearest_surface = false;
  // What the edge and depth knobs move: edge work and the contacts' depths.
  const auto fingerprint = [](const std::vector<StepResult>& run) {
    std::tuple<size_t, size_t, size_t, double> f{};
    for (const StepResult& r : run) {
      std::get<0>(f) += r.stats.edges_tested;
      std::get<1>(f) += r.stats.edges_held;
      std::get<2>(f) += r.contacts.size();
      for (const Contact& k : r.contacts) std::get<3>(f) += k.depth;
    }
    return f;
  };
  const auto reference = run_scene("basic", scene);
  EXPECT_NE(fingerprint(reference), fingerprint(run_scene("basic", Scene{"concave", Mode::automatic, 16, 8})))
      << knob << " changed nothing";
  for (const std::string backend : {"opencl", "opencl-basic"}) {
    SCOPED_TRACE(backend);
    const auto device = run_scene(backend, scene);
    expect_ran_on_devices(device, 2);
    EXPECT_GT(expect_same_run(device, reference), 0u);
  }
}
INSTANTIATE_TEST_SUITE_P(Knobs, KnobVariant,
                         ::testing::Values("edge_contacts", "edges_both_sides", "edges_beside_contacts",
                                           "edge_retest_motion", "nearest_surface"),
                         [](const ::testing::TestParamInfo<std::string>& info) { return info.param; });

// Pairs moving fast: their limits (extension, threshold, walk limit) grow
// with their motion, and the devices derive them from it as the host does
// (rtcd_derive_limits; the setups carry the motion, not the limits).
TEST(OpenCl, FastPairsDeriveTheHostsLimits) {
  Scene scene{"concave", Mode::automatic, 16, 8};
  scene.motion_scale = 12.0;
  const auto slow = run_scene("basic", Scene{"concave", Mode::automatic, 16, 8});
  const auto fast = run_scene("basic", scene);
  for (const std::string backend : {"opencl", "opencl-basic"}) {
    SCOPED_TRACE(backend);
    const auto device = run_scene(backend, scene);
    expect_ran_on_devices(device, 2);
    EXPECT_GT(expect_same_run(device, fast), 0u);
  }
  // The motion mattered: more pairs left their walks (equation 2.1 past
  // the threshold) than in the same scene moving at the family's pace.
  size_t full_slow = 0, full_fast = 0;
  for (size_t s = 1; s < slow.size(); ++s) {
    full_slow += slow[s].stats.pairs_full;
    full_fast += fast[s].stats.pairs_full;
  }
  EXPECT_GT(full_fast, full_slow);
}

// Pairs certified apart (trace_separated_pairs off) are decided on the host
// from the same outcomes: the devices certify, skip and expire the same
// pairs as basic.
TEST(OpenCl, CertifiedPairsEqualBasic) {
  Scene scene{"concave", Mode::automatic, 32, 8};
  scene.config.trace_separated_pairs = false;
  for (const std::string backend : {"opencl", "opencl-basic"}) {
    SCOPED_TRACE(backend);
    const auto device = run_scene(backend, scene);
    EXPECT_GT(expect_same_run(device, run_scene("basic", scene)), 0u);
    size_t certified = 0;
    for (const StepResult& r : device) certified += r.stats.pairs_certified;
    EXPECT_GT(certified, 0u) << "no pair was certified: the comparison would not cover certificates";
  }
}

// A device derives a pair's motion from the poses of the last step and
// this one (rtcd_pair_motion): one that ran nothing last step (the pair's
// boxes apart) is sent the last step's poses with this step's. Two bodies
// rest with their boxes 0.15 apart, then one moves 0.34 into the other's
// box, a motion that widens the pair's distance extension from 0.07 to
// 0.68 (short of its cap) and its predictive rays with it: the device's
// steps equal basic's, bit for bit.
TEST(OpenCl, DevicesIdleLastStepDeriveTheMotionFromItsPoses) {
  const auto run = [](const std::string& backend) {
    const Family f = validation::make_family("concave");
    auto narrow = make_narrow_phase(backend, Config{});
    const ShapeId a = narrow->add_shape(f.a), b = narrow->add_shape(f.b);
    const double apart = f.a->bounds().max.x() - f.b->bounds().min.x() + 0.15;
    const auto at = [](double x) { return Pose{{x, 0, 0}, Eigen::Quaterniond::Identity()}; };
    const BodyId first = narrow->add_body(a, Pose{}), second = narrow->add_body(b, at(apart));
    const std::vector<BodyPair> pairs{{first, second}};
    std::vector<StepResult> steps;
    for (int step = 0; step < 6; ++step) {
      narrow->set_pose(second, at(step < 4 ? apart : apart - 0.3 - 0.01 * step));
      steps.push_back(narrow->detect(pairs));
    }
    return steps;
  };
  const auto device = run("opencl:devices=1"), cpu = run("basic");
  expect_same_run(device, cpu);
  for (size_t s = 0; s < device.size(); ++s) {
    EXPECT_EQ(device[s].stats.cpu_fallback, "") << "step " << s;
    EXPECT_EQ(device[s].stats.devices[0].jobs, s < 4 ? 0u : 2u) << "step " << s;
  }
  EXPECT_GT(device[4].predictive.size(), 0u) << "the motion must show in the predictive rays";
}

// A device finds a full batch's items itself (rtcd_prepare), in room the
// host made from the most items a job its batches held so far; a batch
// that outgrows it is run again, at once, with room for all it found. Two
// bodies touch at their boxes' edges for three steps (few items near the
// overlap), then one moves into the other's middle: that step's batch
// outgrows its room and runs again (a second wait, twice the launches),
// the next fits; every step equals basic's, bit for bit.
TEST(OpenCl, FullBatchesThatOutgrowTheirRoomRunAgain) {
  const auto run = [](const std::string& backend) {
    const Family f = validation::make_family("concave");
    Config config;
    config.mode = Mode::full;
    auto narrow = make_narrow_phase(backend, config);
    const ShapeId a = narrow->add_shape(f.a), b = narrow->add_shape(f.b);
    const double touching = f.a->bounds().max.x() - f.b->bounds().min.x() - 0.02;
    const auto at = [](double x) { return Pose{{x, 0, 0}, Eigen::Quaterniond::Identity()}; };
    const BodyId first = narrow->add_body(a, Pose{}), second = narrow->add_body(b, at(touching));
    const std::vector<BodyPair> pairs{{first, second}};
    std::vector<StepResult> steps;
    for (int step = 0; step < 5; ++step) {
      narrow->set_pose(second, at(step < 3 ? touching : 0.1));
      steps.push_back(narrow->detect(pairs));
    }
    return steps;
  };
  const auto device = run("opencl:devices=1"), cpu = run("basic");
  expect_same_run(device, cpu);
  const DeviceWork& before = device[2].stats.devices[0];
  const DeviceWork& outgrown = device[3].stats.devices[0];
  const DeviceWork& after = device[4].stats.devices[0];
  for (size_t s = 0; s < device.size(); ++s) EXPECT_EQ(device[s].stats.cpu_fallback, "") << "step " << s;
  EXPECT_EQ(before.waits, 1u);
  // Its reports outgrow the bound guessed from the last step too: a third wait.
  EXPECT_EQ(outgrown.waits, 3u) << "the batch outgrew its room: it runs again";
  EXPECT_EQ(outgrown.launches, 2 * before.launches);
  EXPECT_EQ(after.waits, 1u);
  EXPECT_EQ(after.launches, before.launches);
  EXPECT_GT(device[3].contacts.size(), 0u);
}

// The device's BVH traversal is plain C: checked on the host against the
// brute force (bvh_answers.hpp), with the device's stack.
TEST(Bvh, AnswersAsTheBruteForce) {
  size_t stack_needed = 0;
  expect_bvh_answers_as_the_brute_force(stack_needed);
  EXPECT_LE(stack_needed, size_t(RTCD_BVH_STACK)) << "trees deeper than the device's stack";
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
    const auto two = run_scene("opencl", scene), one = run_scene("opencl:devices=1", scene);
    expect_ran_on_devices(two, 2);
    expect_ran_on_devices(one, 1);
    const size_t reported = expect_same_run(two, one);
    EXPECT_GT(reported, 0u);
  }
}

// Bodies added between steps reach the device's table of the bodies'
// shapes (a pair's setup names its bodies only): pairs of a second family,
// added at the third step, step as on `basic`, bit for bit.
TEST(OpenCl, BodiesAddedBetweenStepsEqualBasic) {
  const auto run = [](const std::string& backend) {
    const Family first = validation::make_family("concave"), later = validation::make_family("convex");
    auto narrow = make_narrow_phase(backend, Config{});
    const ShapeId shapes[] = {narrow->add_shape(first.a), narrow->add_shape(first.b), narrow->add_shape(later.a),
                              narrow->add_shape(later.b)};
    std::vector<BodyPair> pairs;
    std::vector<StepResult> steps;
    for (size_t step = 0; step < 5; ++step) {
      if (step == 0 || step == 2) {
        const Family& f = step == 0 ? first : later;
        const ShapeId a = shapes[step == 0 ? 0 : 2], b = shapes[step == 0 ? 1 : 3];
        for (size_t i = 0; i < 12; ++i) {
          const validation::PosePair p = validation::random_poses(f, 5, step * 12 + i);
          pairs.push_back({narrow->add_body(a, p.a), narrow->add_body(b, p.b)});
        }
      }
      steps.push_back(narrow->detect(pairs));
    }
    return steps;
  };
  const auto device = run("opencl:devices=1"), cpu = run("basic");
  expect_ran_on_devices(device, 1);
  ASSERT_EQ(device[2].pairs.size(), 24u);
  EXPECT_GT(expect_same_run(device, cpu), 0u);
  size_t later_contacts = 0;
  for (size_t s = 2; s < cpu.size(); ++s)
    for (const PairResult& p : cpu[s].pairs) later_contacts += p.pair.a >= 24 ? p.contact_count : 0;
  EXPECT_GT(later_contacts, 0u) << "the later pairs must touch, or the test says little";
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

// What driving a device takes is counted per step: the kernels enqueued,
// the copies each way, the host's blocking waits, the bytes, and the
// device's own time from profiling events, summed over the devices in
// StepStats. Today's path enqueues a fixed set of commands a batch,
// whatever its pairs and rays; its bytes grow with them.
TEST(OpenCl, DeviceCommandsAreCountedPerStep) {
  struct Walking {
    size_t launches, writes, reads, waits, bytes_to, bytes_from;
  };
  std::vector<Walking> walking;
  for (const size_t pairs : {2, 16}) {
    SCOPED_TRACE(std::to_string(pairs) + " pairs");
    const auto start = std::chrono::steady_clock::now();
    const auto steps = run_scene("opencl:devices=1", {"concave", Mode::iterative, pairs, 5});
    const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    expect_ran_on_devices(steps, 1);
    double device_seconds = 0;
    for (size_t s = 0; s < steps.size(); ++s) {
      SCOPED_TRACE("step " + std::to_string(s));
      const StepStats& st = steps[s].stats;
      const DeviceWork& w = st.devices.at(0);
      EXPECT_EQ(st.device_launches, w.launches);
      EXPECT_EQ(st.device_writes, w.writes);
      EXPECT_EQ(st.device_reads, w.reads);
      EXPECT_EQ(st.device_waits, w.waits);
      EXPECT_EQ(st.bytes_to_device, w.bytes_to_device);
      EXPECT_EQ(st.bytes_from_device, w.bytes_from_device);
      EXPECT_EQ(st.seconds_device_kernels, w.seconds_kernels);
      ASSERT_GT(w.rays, 0u);
      // Each batch with rays enqueues kernels, copies its jobs up and its
      // outcomes down, and waits for them at least once.
      EXPECT_GE(w.launches, 2u);
      EXPECT_GE(w.writes, 1u);
      EXPECT_GE(w.reads, 1u);
      EXPECT_GE(w.waits, 1u);
      EXPECT_GT(w.bytes_to_device, 0u);
      EXPECT_GT(w.bytes_from_device, 0u);
      // Kernels ran on the device, and took some of its time.
      EXPECT_GT(w.seconds_kernels, 0.0);
      EXPECT_GT(w.seconds_copies, 0.0);
      device_seconds += w.seconds_kernels + w.seconds_copies;
    }
    // One in-order queue runs one command at a time, so its commands' device
    // time fits in the wall time they ran in (a unit slip would not).
    EXPECT_LE(device_seconds, wall);
    // The walking steps after the first (whose rays were kept on the device).
    for (size_t s = 2; s < steps.size(); ++s) {
      const DeviceWork& w = steps[s].stats.devices[0];
      EXPECT_EQ(w.launches, steps[2].stats.devices[0].launches) << "step " << s;
      EXPECT_EQ(w.waits, steps[2].stats.devices[0].waits) << "step " << s;
    }
    const DeviceWork& w = steps.back().stats.devices[0];
    walking.push_back({w.launches, w.writes, w.reads, w.waits, w.bytes_to_device, w.bytes_from_device});
  }
  // The same commands and waits for 2 pairs and for 16; more bytes.
  EXPECT_EQ(walking[0].launches, walking[1].launches);
  EXPECT_EQ(walking[0].writes, walking[1].writes);
  EXPECT_EQ(walking[0].reads, walking[1].reads);
  EXPECT_EQ(walking[0].waits, walking[1].waits);
  EXPECT_LT(walking[0].bytes_to, walking[1].bytes_to);
  EXPECT_LT(walking[0].bytes_from, walking[1].bytes_from);
}

// A walking step's outcomes are counted and laid out on the device: what
// comes back before the step ends is the step's counters, a summary a job
// and the outcomes that report (contacts, predictive rays) whole, each with
// its place; the other kept rays stay on the device, and their walk starts
// (12 bytes: vertex, exit and entry triangles) come back apart, on the
// recovery queue nothing waits for. The CPU's output, counters included,
// is unchanged (the bit-for-bit suites); a wrong place or a lost watched
// ray would show there.
TEST(OpenCl, WalksReadBackReportsWholeAndWalkStartsOnlyForRecovery) {
  const size_t pairs = 16;
  const auto steps = run_scene("opencl:devices=1", {"concave", Mode::iterative, pairs, 6});
  expect_ran_on_devices(steps, 1);
  constexpr size_t kCounters = 8 * 24, kSummary = 8, kKept = 12, kReport = 40;
  // Up: every body's pose and a reference a pair to its row of the last
  // step's pair table (its bodies and kept rays: rtcd_pair_ref), with its
  // flags and motion; both directions' parameters, first items and frames
  // are made on the device, the bodies' shapes went up with the first
  // step, and the walks' rays are there already.
  constexpr size_t kPose = 56, kPair = 8;
  size_t walked = 0, reported = 0;
  for (size_t s = 2; s < steps.size(); ++s) {
    SCOPED_TRACE("step " + std::to_string(s));
    const StepResult& last = steps[s - 1];
    const StepStats& st = steps[s].stats;
    ASSERT_EQ(st.pairs_iterative, pairs);
    // This step walks every ray the last one kept.
    const size_t reports = last.contacts.size() + last.predictive.size();
    const size_t items = reports + last.stats.rays_watched;
    EXPECT_LE(st.devices[0].rays, items);
    // The reports are read up to a bound guessed from the last step's.
    const size_t report_read = std::min<size_t>(items, size_t(1.25 * double(reports)) + 64);
    EXPECT_EQ(st.bytes_from_device, kCounters + kSummary * 2 * pairs + kReport * report_read);
    // The rays the step keeps (those that report and the watched ones) lie
    // one job after another on the device: all read back apart.
    const size_t kept = steps[s].contacts.size() + steps[s].predictive.size() + st.rays_watched;
    EXPECT_EQ(st.bytes_recovery, kKept * kept);
    EXPECT_EQ(st.bytes_to_device, kPose * 2 * pairs + kPair * pairs);
    EXPECT_EQ(st.device_waits, 1u);
    walked += items;
    reported += steps[s].contacts.size() + steps[s].predictive.size();
  }
  // The scene reports a part of what it walks, and the rest stays on the
  // device.
  EXPECT_GT(reported, 0u);
  EXPECT_LT(reported, walked);
}

// A full step reads its reports up to a bound from each pair's reports the
// step before (where the pair ran before: a pair's reports change little
// from step to step), and the rest, if any, after a second wait; the
// counters, the batch's item count and a summary a job besides.
TEST(OpenCl, FullStepsReadReportsUpToTheirPairsLastCount) {
  const size_t pairs = 16;
  const auto steps = run_scene("opencl:devices=1", {"concave", Mode::full, pairs, 6});
  expect_ran_on_devices(steps, 1);
  constexpr size_t kCounters = 8 * 24, kSummary = 8, kReport = 40, kItemCount = 4, kPose = 56, kFullPair = 12;
  size_t short_bounds = 0;
  for (size_t s = 1; s < steps.size(); ++s) {
    SCOPED_TRACE("step " + std::to_string(s));
    const StepResult& last = steps[s - 1];
    const StepStats& st = steps[s].stats;
    ASSERT_EQ(st.pairs_full, pairs);
    const size_t bound = size_t(1.25 * double(last.contacts.size() + last.predictive.size())) + 64;
    const size_t reports = steps[s].contacts.size() + steps[s].predictive.size();
    EXPECT_EQ(st.bytes_from_device,
              kCounters + kItemCount + kSummary * 2 * pairs + kReport * std::max(bound, reports));
    EXPECT_EQ(st.device_waits, reports > bound ? 2u : 1u);
    // Up: every body's pose and a pair's bodies and flags (rtcd_full_pair);
    // the device finds the pairs' items.
    EXPECT_EQ(st.bytes_to_device, kPose * 2 * pairs + kFullPair * pairs);
    short_bounds += reports > bound;
  }
  EXPECT_GT(steps.back().contacts.size(), 64u) << "too few reports: the bound's guess would not matter";
  EXPECT_EQ(short_bounds, 0u) << "a resting scene's reports stay within their last count's bound";
}

// A step waits once a device: the device lays out the full batch's ray
// list itself, the walks are enqueued behind it, and the host reads the
// counts and the outcomes (up to a bound guessed from the last full batch)
// after one wait. The first full batch has no guess (64 rays), so the rest
// of its outcomes takes a second read and wait, and its room for items is
// a guess too (64 a job), which it may outgrow and run again after another;
// the output is the CPU's either way (the bit-for-bit suites).
TEST(OpenCl, StepsWaitOnce) {
  for (const Mode mode : {Mode::full, Mode::automatic}) {
    SCOPED_TRACE(mode_name(mode));
    Scene scene{"concave", mode, 16, 12};
    scene.config.displacement_threshold = 2.5 * validation::make_family("concave").step_motion();
    const auto steps = run_scene("opencl:devices=1", scene);
    expect_ran_on_devices(steps, 1);
    ASSERT_GT(steps[0].stats.devices[0].rays, 64u);
    EXPECT_GE(steps[0].stats.devices[0].waits, 2u);
    EXPECT_LE(steps[0].stats.devices[0].waits, 3u);
    size_t both = 0;
    for (size_t s = 1; s < steps.size(); ++s) {
      EXPECT_EQ(steps[s].stats.devices[0].waits, 1u) << "step " << s;
      both += steps[s].stats.pairs_full > 0 && steps[s].stats.pairs_iterative > 0;
    }
    if (mode == Mode::automatic) {
      EXPECT_GT(both, 0u) << "no step had both batches: the test shows nothing";
    }
  }
}

// A pair stays on one device while it stays in the broad phase: the full
// steps equation 2.1 sends it back to run where its walks ran, both of its
// directions together, and the pairs are spread over both devices. The CPU
// backends say -1.
TEST(OpenCl, PairsKeepTheirDevice) {
  Scene scene{"concave", Mode::automatic, 24, 40};
  // Walks end every few steps, so the pairs are traced in full again often.
  scene.config.displacement_threshold = 2.5 * validation::make_family("concave").step_motion();
  const auto steps = run_scene("opencl", scene);
  expect_ran_on_devices(steps, 2);
  size_t sent_back = 0, walked = 0;
  std::set<int32_t> used;
  for (const PairResult& p : steps[0].pairs) used.insert(p.device);
  EXPECT_EQ(used, (std::set<int32_t>{0, 1}));
  for (size_t s = 1; s < steps.size(); ++s) {
    sent_back += steps[s].stats.fallbacks_to_full;
    walked += steps[s].stats.pairs_iterative;
    for (size_t i = 0; i < steps[s].pairs.size(); ++i)
      EXPECT_EQ(steps[s].pairs[i].device, steps[0].pairs[i].device) << "step " << s << ", pair " << i;
  }
  EXPECT_GT(sent_back, 24u) << "few walks ended: the test shows nothing";
  EXPECT_GT(walked, 24u);
  const auto cpu = run_scene("basic", {"concave", Mode::full, 2, 1});
  for (const PairResult& p : cpu[0].pairs) EXPECT_EQ(p.device, -1);
}

// Both layouts (by default grid for iterative batches, compacted for full
// ones) trace the same rays in the same order, on BVH and brute force.
TEST(OpenCl, LayoutsAgree) {
  for (Mode mode : {Mode::full, Mode::automatic}) {
    const Scene scene{"concave", mode, 24, 4};
    const auto by_mode = run_scene("opencl", scene);
    expect_ran_on_devices(by_mode, 2);
    for (const std::string layout : {"grid", "compact"}) {
      const auto laid_out = run_scene("opencl:layout=" + layout, scene);
      expect_ran_on_devices(laid_out, 2);
      EXPECT_GT(expect_same_run(laid_out, by_mode), 0u) << layout;
    }
  }
  for (Mode mode : {Mode::full, Mode::iterative}) {
    const Scene scene{"primitives", mode, 24, 4};
    const auto grid = run_scene("opencl-basic:layout=grid:devices=0", scene);
    expect_ran_on_devices(grid, 1);
    EXPECT_GT(expect_same_run(grid, run_scene("basic", scene)), 0u);
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
  expect_ran_on_devices(placed_by_host, 2);
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
  // The statistics say so too, from the failing step on: a setup fault from
  // the first step, the mid-step one after the devices ran the first step.
  size_t first_on_cpu = 0;
  while (first_on_cpu < faulted.size() && faulted[first_on_cpu].stats.cpu_fallback.empty()) ++first_on_cpu;
  EXPECT_EQ(first_on_cpu, fault == OpenClFault::mid_step ? 1u : 0u);
  for (size_t s = first_on_cpu; s < faulted.size(); ++s)
    EXPECT_NE(faulted[s].stats.cpu_fallback.find(reason), std::string::npos)
        << "step " << s << ": '" << faulted[s].stats.cpu_fallback << "'";
  if (fault == OpenClFault::mid_step) expect_ran_on_devices({faulted.front()}, 2);
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

// A fault in a walked batch while the step's full batch is still on the
// devices: the CPU runs both from their jobs, and the output is the
// uninterrupted one. The scene sends pairs back to full tracing while
// others walk, so some step has both batches.
TEST(OpenCl, FaultBehindAPendingFullBatchFinishesBothOnTheCpu) {
  Scene scene{"concave", Mode::automatic, 16, 8};
  scene.config.displacement_threshold = 0.004;  // most pairs sent back within a few steps
  const auto reference = run_scene("basic", scene);
  inject_opencl_fault(OpenClFault::behind_full);
  ::testing::internal::CaptureStderr();
  const auto faulted = run_scene("opencl-basic", scene);
  const std::string err = ::testing::internal::GetCapturedStderr();
  inject_opencl_fault(OpenClFault::none);
  EXPECT_NE(err.find("during a step"), std::string::npos) << err;
  size_t struck = 0;
  while (struck < faulted.size() && faulted[struck].stats.cpu_fallback.empty()) ++struck;
  ASSERT_LT(struck, faulted.size()) << "the fault never struck";
  EXPECT_GT(faulted[struck].stats.pairs_full, 0u) << "step " << struck << ": no full batch was pending";
  EXPECT_GT(faulted[struck].stats.pairs_iterative, 0u) << "step " << struck;
  expect_ran_on_devices(std::vector<StepResult>(faulted.begin(), faulted.begin() + long(struck)), 2);
  EXPECT_GT(expect_same_run(faulted, reference), 0u);
}

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
