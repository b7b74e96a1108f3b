// Recordings and replays: a recording gives back exactly what the simulation
// saw; every engine replays the same steps; stateful configurations are never
// sampled; phases and motion come from the recorded physics; bad recordings
// are refused by name; `rtcd bench` writes every table.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <sstream>
#include <unistd.h>

#include <gtest/gtest.h>

#include "rtcd/experiments/bench.hpp"
#include "rtcd/experiments/replay.hpp"
#include "rtcd/sim/recording.hpp"
#include "rtcd/sim/simulation.hpp"

namespace rtcd::test {
namespace {

namespace fs = std::filesystem;
using experiments::Engine;
using experiments::ReplayConfig;

// Eight blobs dropped on the ground in two layers: contacts with the ground,
// then between blobs.
const char* kPile = R"({
  "time_step": 0.016666666666666666, "steps": 50, "seed": 4,
  "effects": ["gravity", "contacts", "friction", "predictive", "projected"],
  "narrow_phase": {"distance_extension": 0.05, "displacement_threshold": 0.02},
  "bodies": [{"blob": {"triangles": 200, "seed": 3, "radius": 0.25}, "count": 8,
              "grid": {"cells": [2, 2, 2], "origin": [-0.26, -0.26, 0.3], "spacing": [0.52, 0.52, 0.45],
                       "random_orientation": true}}]
})";

struct TempDir {
  fs::path path;
  TempDir() {
    path = fs::temp_directory_path() / ("rtcd_bench_test_" + std::to_string(::getpid()) + "_" +
                                        ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(path);
    fs::create_directories(path);
  }
  ~TempDir() { fs::remove_all(path); }
};

// Simulates kPile (or `json`) into a recording; returns its path.
std::string record(const TempDir& dir, const std::string& json = kPile,
                   std::vector<std::vector<Pose>>* poses = nullptr, std::vector<std::vector<BodyPair>>* pairs = nullptr) {
  const std::string scene_path = (dir.path / "scene.json").string();
  std::ofstream(scene_path) << json;
  const sim::Scene scene = sim::parse_scene(json, scene_path);
  const std::string path = (dir.path / "run.rtcdrec").string();
  sim::RecordingWriter writer(path, scene_path, json);
  sim::Simulation simulation(scene);
  for (uint64_t i = 0; i < scene.steps; ++i) {
    simulation.step();
    writer.append(simulation);
    if (poses) {
      poses->emplace_back();
      simulation.shape_poses(poses->back());
    }
    if (pairs) pairs->emplace_back(simulation.last_pairs().begin(), simulation.last_pairs().end());
  }
  writer.close();
  return path;
}

std::string bytes_of(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

TEST(Recording, GivesBackThePosesAndPairsTheSimulationSaw) {
  TempDir dir;
  std::vector<std::vector<Pose>> poses;
  std::vector<std::vector<BodyPair>> pairs;
  const sim::Recording r = sim::Recording::read(record(dir, kPile, &poses, &pairs));
  ASSERT_EQ(r.steps().size(), 50u);
  EXPECT_EQ(r.kinds().size(), 9u);  // the ground and eight blobs
  EXPECT_EQ(r.kinds()[0], sim::Simulation::kGroundKind);
  sim::Recording::Cursor cursor(r);
  sim::RecordedFrame frame;
  size_t steps_with_pairs = 0;
  while (cursor.next(frame)) {
    const uint64_t i = cursor.index();
    ASSERT_EQ(frame.poses.size(), poses[i].size());
    for (size_t b = 0; b < frame.poses.size(); ++b) {
      EXPECT_LT((frame.poses[b].position - poses[i][b].position).norm(), 1e-6);
      EXPECT_LT(frame.poses[b].orientation.angularDistance(poses[i][b].orientation), 1e-6);
    }
    std::vector<BodyPair> expected;
    for (BodyPair p : pairs[i]) expected.push_back({std::min(p.a, p.b), std::max(p.a, p.b)});
    std::sort(expected.begin(), expected.end(), [](BodyPair x, BodyPair y) { return std::pair(x.a, x.b) < std::pair(y.a, y.b); });
    ASSERT_EQ(frame.pairs.size(), expected.size()) << "step " << i;
    for (size_t k = 0; k < expected.size(); ++k) {
      EXPECT_EQ(frame.pairs[k].a, expected[k].a);
      EXPECT_EQ(frame.pairs[k].b, expected[k].b);
    }
    EXPECT_EQ(r.steps()[i].pairs, expected.size());
    steps_with_pairs += !expected.empty();
  }
  EXPECT_GT(steps_with_pairs, 25u);
  EXPECT_GT(r.steps().back().ground_contacts, 0u);
}

TEST(Recording, BodiesThatAppearLaterKeepTheirIds) {
  TempDir dir;
  const sim::Recording r = sim::Recording::read(record(dir, R"({
    "time_step": 0.016666666666666666, "steps": 30,
    "effects": ["gravity", "contacts", "predictive", "projected"],
    "bodies": [{"sphere": 0.1, "count": 3, "emitter": {"rate": 10, "start": 0.2, "centre": [0, 0, 1], "radius": 0.5,
                                                       "angular_speed": 2}},
               {"box": [0.1, 0.1, 0.1], "pose": {"position": [0, 0, 2]}}]
  })"));
  ASSERT_EQ(r.kinds().size(), 5u);
  EXPECT_EQ(r.kinds()[1], 1u);  // the box is made first, then the emitter's spheres as they appear
  EXPECT_EQ(r.kinds()[2], 0u);
  EXPECT_EQ(r.steps()[0].bodies, 2u);
  // Sphere k appears at 0.2 + k / 10 s: on step 12, 18, 24.
  EXPECT_EQ(r.steps()[12].bodies, 3u);
  EXPECT_EQ(r.steps()[29].bodies, 5u);
}

TEST(Recording, BadFilesAreRefusedByName) {
  TempDir dir;
  const std::string good = bytes_of(record(dir));
  const auto refused = [&](const std::string& bytes, const std::string& expected) {
    try {
      sim::Recording::parse(bytes, "run.rtcdrec");
      ADD_FAILURE() << "accepted; expected " << expected;
    } catch (const sim::RecordingError& e) {
      EXPECT_NE(std::string(e.what()).find(expected), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find("run.rtcdrec"), std::string::npos) << e.what();
    }
  };
  refused("", "truncated in the header");
  refused("RTCDREC2" + good.substr(8), "not an rtcd recording");
  refused(good.substr(0, good.size() - 3), "step 49: truncated");
  std::string bad_tag = good;
  const size_t first_step = good.find("STEP");
  ASSERT_NE(first_step, std::string::npos);
  bad_tag[first_step] = 'X';
  refused(bad_tag, "step 0: no step tag");
  EXPECT_THROW(sim::Recording::read((dir.path / "missing.rtcdrec").string()), sim::RecordingError);
}

ReplayConfig ours(const std::string& backend, Mode mode, uint64_t every = 1) {
  ReplayConfig c;
  c.label = backend + " " + to_string(mode);
  c.backend = backend;
  c.config.distance_extension = 0.05;
  c.config.displacement_threshold = 0.02;
  c.config.mode = mode;
  c.every = every;
  return c;
}

TEST(Replay, EveryEngineSeesTheSameStepsAndTheTracersAgree) {
  TempDir dir;
  const sim::Recording r = sim::Recording::read(record(dir));
  ReplayConfig gimpact, fcl;
  gimpact.label = "GIMPACT";
  gimpact.engine = Engine::gimpact;
  gimpact.every = 5;
  fcl.label = "FCL";
  fcl.engine = Engine::fcl;
  fcl.every = 5;
  experiments::ReplayOptions options;
  options.judge_every = 5;
  const auto runs = experiments::replay(
      r, {ours("basic", Mode::full), ours("embree", Mode::full), ours("embree", Mode::automatic), gimpact, fcl},
      options);
  ASSERT_EQ(runs.size(), 5u);
  size_t deep = 0, colliding_steps = 0;
  for (uint64_t s = 0; s < r.steps().size(); ++s) {
    const auto& basic = runs[0].steps[s];
    const auto& embree = runs[1].steps[s];
    ASSERT_TRUE(basic.ran && embree.ran && runs[2].steps[s].ran);
    EXPECT_EQ(basic.pairs, r.steps()[s].pairs);
    EXPECT_EQ(basic.contacts, embree.contacts) << "step " << s;
    EXPECT_EQ(basic.contact_digest, embree.contact_digest) << "the same contacts (bodies, kind, item, face), step " << s;
    EXPECT_NEAR(basic.depth_sum, embree.depth_sum, 1e-4 * (1 + basic.depth_sum));
    EXPECT_EQ(runs[3].steps[s].ran, s % 5 == 0);
    EXPECT_EQ(runs[4].steps[s].ran, s % 5 == 0);
    if (s % 5 == 0) {
      EXPECT_TRUE(embree.judged);
      EXPECT_EQ(embree.missed, 0u) << "full tracing misses nothing, step " << s;
      EXPECT_EQ(embree.false_rays, 0u) << "full tracing reports no vertex outside, step " << s;
      EXPECT_LE(runs[2].steps[s].missed, runs[2].steps[s].deep / 100) << "step " << s;
      EXPECT_EQ(runs[2].steps[s].false_rays, 0u) << "verified walks report no vertex outside, step " << s;
      deep += embree.deep;
      if (embree.colliding > 0) {
        ++colliding_steps;
        EXPECT_GT(runs[3].steps[s].colliding, 0u) << "GIMPACT, step " << s;
        EXPECT_GT(runs[4].steps[s].colliding, 0u) << "FCL, step " << s;
      }
    }
  }
  EXPECT_GT(deep, 0u);
  EXPECT_GT(colliding_steps, 3u);
  EXPECT_EQ(runs[3].engine_name, "bullet-gimpact");
}

// Blobs dropped from staggered heights that land, bounce and roll apart:
// pairs join the broad phase's set and leave it all along the run.
const char* kTumble = R"({
  "time_step": 0.016666666666666666, "steps": 200, "seed": 9,
  "effects": ["gravity", "contacts", "friction", "predictive", "projected"],
  "narrow_phase": {"distance_extension": 0.05, "displacement_threshold": 0.02},
  "bodies": [{"blob": {"triangles": 200, "seed": 5, "radius": 0.25}, "count": 16,
              "grid": {"cells": [4, 2, 2], "origin": [-0.78, -0.26, 0.3], "spacing": [0.52, 0.52, 0.6],
                       "random_orientation": true}}]
})";

// On two devices, a pair runs on one device from the step it
// joins the broad phase's set until it leaves it, over 200 recorded steps
// in which pairs come and go (a pair that leaves and comes back may move).
TEST(Replay, OpenClPairsKeepTheirDeviceWhileInTheBroadPhase) {
  TempDir dir;
  const sim::Recording r = sim::Recording::read(record(dir, kTumble));
  ASSERT_EQ(r.steps().size(), 200u);
  std::map<uint64_t, int32_t> device, present;  // by pair_key: its device while it stays; this step's pairs
  std::set<int32_t> used;
  size_t stayed = 0, joined_later = 0, left = 0, on_cpu = 0;
  experiments::ReplayOptions options;
  options.observe = [&](uint64_t step, const StepResult& result) {
    present.clear();
    on_cpu += !result.stats.cpu_fallback.empty();
    for (const PairResult& p : result.pairs) {
      const uint64_t key = pair_key(p.pair.a, p.pair.b);
      const auto before = device.find(key);
      if (before == device.end()) {
        joined_later += step > 0;
        present[key] = p.device;
        continue;
      }
      ++stayed;
      EXPECT_EQ(p.device, before->second) << "step " << step << ", bodies " << p.pair.a << " and " << p.pair.b;
      present[key] = before->second;
    }
    for (const auto& [pair, d] : device) left += !present.count(pair);
    for (const auto& [pair, d] : present) used.insert(d);
    device.swap(present);
  };
  experiments::replay(r, {ours("opencl", Mode::automatic)}, options);
  EXPECT_EQ(on_cpu, 0u) << "steps ran on the CPU fallback: no device to keep";
  EXPECT_EQ(used, (std::set<int32_t>{0, 1})) << "the pairs did not spread over both devices";
  EXPECT_GT(stayed, 500u);
  EXPECT_GT(joined_later, 5u) << "few pairs joined during the run: the test shows little";
  EXPECT_GT(left, 10u) << "few pairs left during the run: the test shows little";
}

TEST(Replay, StatefulConfigurationsAreNeverSampled) {
  TempDir dir;
  const sim::Recording r = sim::Recording::read(record(dir));
  for (Mode m : {Mode::automatic, Mode::iterative})
    EXPECT_THROW(experiments::replay(r, {ours("embree", m, 2)}), UsageError);
  EXPECT_NO_THROW(experiments::replay(r, {ours("embree", Mode::full, 2)}));
}

TEST(Replay, AConfigurationOverItsBudgetStopsForGood) {
  TempDir dir;
  const sim::Recording r = sim::Recording::read(record(dir));
  ReplayConfig c = ours("basic", Mode::full);
  c.budget_seconds = 1e-9;
  const auto runs = experiments::replay(r, {c});
  ASSERT_TRUE(runs[0].stopped());
  EXPECT_EQ(runs[0].stopped_at, 1u);  // the first step spends the budget
  for (uint64_t s = runs[0].stopped_at; s < r.steps().size(); ++s) EXPECT_FALSE(runs[0].steps[s].ran);
}

TEST(Phases, FromPairsGroundContactAndKineticEnergy) {
  std::vector<sim::RecordedStep> steps(20);
  for (uint64_t i = 0; i < 20; ++i) {
    steps[i].step = i;
    steps[i].pairs = i >= 2 ? 10 : 0;
    steps[i].ground_contacts = i >= 5 ? 4 : 0;
    steps[i].kinetic_energy = i <= 7 ? double(i) : 7.0 * std::pow(0.7, double(i - 7));
  }
  const experiments::Phases p = experiments::find_phases(steps, 0.1);
  EXPECT_EQ(p.a_begin, 2u);
  EXPECT_EQ(p.b_begin, 5u);
  EXPECT_EQ(p.c_begin, 14u);  // 7 * 0.7^7 = 0.576 < 0.7, the first below a tenth of the peak
  EXPECT_EQ(p.end, 20u);
  EXPECT_EQ(p.of(1), '-');
  EXPECT_EQ(p.of(4), 'A');
  EXPECT_EQ(p.of(13), 'B');
  EXPECT_EQ(p.of(14), 'C');
  for (auto& s : steps) s.ground_contacts = 0;
  const experiments::Phases never = experiments::find_phases(steps, 0.1);
  EXPECT_EQ(never.b_begin, 20u);
  EXPECT_EQ(never.c_begin, 20u);
}

TEST(Motion, IsTheFastestBodysStep) {
  TempDir dir;
  const sim::Recording r = sim::Recording::read(record(dir, R"({
    "time_step": 0.01, "steps": 20,
    "effects": ["contacts", "predictive", "projected"],
    "ground": false,
    "bodies": [{"sphere": 0.2, "velocity": [3, 0, 0], "pose": {"position": [0, 0, 0]}},
               {"sphere": 0.2, "velocity": [0, 1, 0], "pose": {"position": [0, 5, 0]}}]
  })"));
  const experiments::Motion m = experiments::largest_motion(r);
  EXPECT_NEAR(m.largest, 0.03, 1e-5);
  EXPECT_NEAR(m.speed, 3.0, 1e-3);
  EXPECT_EQ(m.body, 0u);
}

// The whole bench on the first 40 steps of the small avalanche: every table
// is written.
TEST(Bench, WritesEveryTable) {
  TempDir dir;
  experiments::BenchOptions o;
  o.scene = std::string(RTCD_DATA_DIR) + "/scenes/avalanche_small.json";
  o.steps = 40;
  o.out = (dir.path / "out").string();
  o.seeds = 2;
  o.gimpact_host_steps = 20;
  o.command = "test";
  const std::string report = experiments::run_bench(o);
  std::ifstream in(report);
  std::stringstream text;
  text << in.rdbuf();
  for (const char* section : {"Table 2.1", "The peak step", "Figure 2.12", "Figure 2.13", "Figure 2.14", "Peers",
                              "Table 2.3", "Table 2.4", "Accuracy against time", "Largest per-step motion", "Phases:"})
    EXPECT_NE(text.str().find(section), std::string::npos) << section;
  for (const char* file : {"recording.rtcdrec", "table_2_1.csv", "table_2_1_speedups.csv", "figure_2_12.csv",
                           "figure_2_14_speedups.csv", "peers.csv", "table_2_3.csv", "table_2_4.csv", "accuracy.csv",
                           "replay_steps.csv", "host_steps.csv", "simulations.csv"})
    EXPECT_TRUE(fs::exists(fs::path(o.out) / file)) << file;
  // Table 2.4 as the scene runs, then as the thesis ran it, each from its own simulations.
  std::ifstream t4(fs::path(o.out) / "table_2_4.csv");
  std::vector<std::string> rows;
  for (std::string row; std::getline(t4, row);) rows.push_back(row);
  ASSERT_EQ(rows.size(), 3u);
  EXPECT_NE(rows[1].find("8 points per pair"), std::string::npos) << rows[1];
  EXPECT_NE(rows[2].find("as the thesis ran (no speculative contacts, 4 points per pair)"), std::string::npos) << rows[2];
  EXPECT_EQ(rows[2].find("blew up"), std::string::npos) << rows[2];
  // The projected depth of the same simulations, the thesis' two among them.
  std::ifstream tp(fs::path(o.out) / "projected_interpenetration.csv");
  std::string header, figures;
  std::getline(tp, header);
  std::getline(tp, figures);
  EXPECT_NE(header.find("standard (as the thesis ran),projected (as the thesis ran)"), std::string::npos) << header;
  EXPECT_EQ(std::count(figures.begin(), figures.end(), '('), 7) << figures;
  EXPECT_EQ(figures.find("blew up"), std::string::npos) << figures;
  // Replaying the recording gives the same tables' shape without simulating it again.
  experiments::BenchOptions again = o;
  again.scene.clear();
  again.replay = (fs::path(o.out) / "recording.rtcdrec").string();
  again.out = (dir.path / "again").string();
  again.seeds = 1;
  EXPECT_NO_THROW(experiments::run_bench(again));
  EXPECT_FALSE(fs::exists(fs::path(again.out) / "recording.rtcdrec"));
  std::ifstream steps(fs::path(again.out) / "host_steps.csv");
  std::string line;
  size_t rtcd_rows = 0;
  while (std::getline(steps, line)) rtcd_rows += line.rfind("rtcd,", 0) == 0;
  EXPECT_EQ(rtcd_rows, 20u);  // the host comparison covers the GIMPACT host's 20 steps
}

}  // namespace
}  // namespace rtcd::test
