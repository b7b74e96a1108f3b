// The `rtcd` command: outputs, sequences, and exit code 2 on every bad input.
#include <algorithm>
#include <cmath>
#include <unistd.h>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>
#include <tuple>

#include <assimp/Importer.hpp>
#include <assimp/scene.h>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "command.hpp"
#include "rtcd/config.hpp"
#include "rtcd/distance_bound.hpp"

namespace {

using rtcd::test::Outcome;

Outcome run(const std::string& args) { return rtcd::test::run_command(args); }

const std::string data = std::string(RTCD_DATA_DIR) + "/meshes/";

TEST(Cli, BackendsJson) {
  const Outcome r = run("backends --json");
  ASSERT_EQ(r.code, 0) << r.out;
  const auto j = nlohmann::json::parse(r.out);
  ASSERT_TRUE(j.is_array());
  bool basic = false;
  for (const auto& b : j) basic |= b["name"] == "basic" && b["usable"] == true;
  EXPECT_TRUE(basic);
}

// A's four +x corners are 0.1 inside B's faces x, y and z alike: the ray
// contact runs 0.1 * sqrt(3) along the corner's diagonal to x = 0.4 (the
// thesis' contact, --no-nearest-surface); the nearest surface is 0.1 away.
TEST(Cli, QueryHandComputedCubesJson) {
  for (const std::string& pair : {data + "box.obj box:0.6,0.6,0.6", std::string("box:0.5,0.5,0.5 box:0.6,0.6,0.6")})
    for (const bool rays : {true, false}) {
      const Outcome r =
          run("query " + pair + " --pose-b \"1 0 0 1 0 0 0\" --json" + (rays ? " --no-nearest-surface" : ""));
      ASSERT_EQ(r.code, 0) << r.out;
      const auto j = nlohmann::json::parse(r.out);
      EXPECT_TRUE(j["colliding"].get<bool>());
      ASSERT_EQ(j["contacts"].size(), 4u);
      for (const auto& c : j["contacts"]) {
        EXPECT_EQ(c["source"], "a");
        EXPECT_NEAR(c["depth"].get<double>(), rays ? 0.1 * std::sqrt(3.0) : 0.1, 1e-6);
        EXPECT_NEAR(c["projected_depth"].get<double>(), 0.1, 1e-6);
        if (rays) {
          EXPECT_NEAR(c["normal"][0].get<double>(), -1.0, 1e-6);
        }
      }
    }
}

// docs/knobs.md holds `rtcd knobs` as it prints: the table is the one
// source, and the docs fail here when they disagree with it.
TEST(Cli, KnobsDocIsTheTable) {
  const Outcome r = run("knobs");
  ASSERT_EQ(r.code, 0);
  std::ifstream file(RTCD_DATA_DIR "/../docs/knobs.md");
  std::stringstream text;
  text << file.rdbuf();
  const std::string doc = text.str(), begin = "<!-- rtcd knobs:begin -->\n", end = "<!-- rtcd knobs:end -->";
  const size_t from = doc.find(begin), to = doc.find(end);
  ASSERT_NE(from, std::string::npos);
  ASSERT_NE(to, std::string::npos);
  EXPECT_EQ(doc.substr(from + begin.size(), to - from - begin.size()), r.out)
      << "docs/knobs.md disagrees with the table: regenerate it from `rtcd knobs`";
}

// Each --no-KNOB option's help begins with what turning the knob off does
// (the knob table's `off`), in every command that takes the knobs.
TEST(Cli, SwitchHelpSaysWhatOffDoes) {
  for (const std::string command : {"query", "validate", "replay"}) {
    const Outcome r = run(command + " --help");
    ASSERT_EQ(r.code, 0) << r.out;
    size_t switches = 0;
    for (const rtcd::Knob& knob : rtcd::knobs()) {
      if (knob.type != rtcd::KnobType::flag) continue;
      ++switches;
      ASSERT_NE(knob.off, nullptr) << knob.name;
      std::string option = "--no-" + std::string(knob.name);
      std::replace(option.begin(), option.end(), '_', '-');
      const size_t at = r.out.find(option + " ");
      ASSERT_NE(at, std::string::npos) << command << " lacks " << option;
      const size_t help = r.out.find_first_not_of(' ', at + option.size());
      EXPECT_EQ(r.out.compare(help, std::strlen(knob.off), knob.off), 0)
          << command << " " << option << ": " << r.out.substr(help, r.out.find('\n', help) - help);
    }
    EXPECT_GE(switches, 5u);
  }
}

TEST(Cli, VersionIsThePackages) {
  const Outcome r = run("--version");
  EXPECT_EQ(r.code, 0);
  EXPECT_EQ(r.out, "rtcd " RTCD_VERSION "\n");
}

TEST(Cli, QueryTableOnCommittedMeshes) {
  const Outcome r = run("query " + data + "blob_902.obj " + data + "stream_2130.obj --pose-b \"1.2 0 0 1 0 0 0\"");
  ASSERT_EQ(r.code, 0) << r.out;
  EXPECT_NE(r.out.find("colliding: yes"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("depth"), std::string::npos);
}

class CliFiles : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = std::filesystem::temp_directory_path() / ("rtcd_cli_" + std::to_string(::getpid()));
    std::filesystem::create_directories(dir_);
  }
  void TearDown() override { std::filesystem::remove_all(dir_); }
  std::string write(const std::string& name, const std::string& text) {
    std::ofstream(dir_ / name) << text;
    return (dir_ / name).string();
  }
  std::filesystem::path dir_;
};

// The pair state carries across a sequence: the second step is iterative and
// predictive rays catch the new contacts (B approaching A, as in Figure 2.4).
TEST_F(CliFiles, SequenceCarriesPairState) {
  const std::string seq = write("seq.json", R"([{"pose_a": [0,0,0,1,0,0,0], "pose_b": [1.13,0,0,1,0,0,0]},
                                                 {"pose_a": [0,0,0,1,0,0,0], "pose_b": [1.09,0,0,1,0,0,0]}])");
  const Outcome r = run("query " + data + "box.obj box:0.6,0.6,0.6 --sequence " + seq + " --json");
  ASSERT_EQ(r.code, 0) << r.out;
  const auto j = nlohmann::json::parse(r.out);
  ASSERT_EQ(j.size(), 2u);
  EXPECT_EQ(j[0]["mode"], "full");
  EXPECT_FALSE(j[0]["colliding"].get<bool>());
  EXPECT_EQ(j[0]["predictive"].size(), 4u);
  EXPECT_EQ(j[1]["mode"], "iterative");
  EXPECT_EQ(j[1]["contacts"].size(), 4u);
  const Outcome off = run("query " + data + "box.obj box:0.6,0.6,0.6 --sequence " + seq + " --json --no-predictive");
  EXPECT_EQ(nlohmann::json::parse(off.out)[1]["contacts"].size(), 0u);
}

TEST_F(CliFiles, EveryBadInputExitsWith2AndOneClearLine) {
  const std::string box = data + "box.obj";
  const std::string garbage = write("garbage.obj", "v 1 2\nf 1 2 9\n");
  const std::string flipped = write("flipped.off", "OFF\n4 4 0\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 2 1\n3 0 1 3\n3 0 2 3\n3 1 2 3\n");
  const std::string bad_json = write("bad.json", "[{\"pose_a\": [0,0,0,1,0,0,0]}");
  const std::string short_pose = write("short.json", R"([{"pose_a": [0,0,0,1,0,0], "pose_b": [0,0,0,1,0,0,0]}])");
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"query /nonexistent.obj " + box, "no such file"},
      {"query " + garbage + " " + box, "garbage.obj"},
      {"query " + flipped + " " + box, "winding"},
      {"query " + box + " " + box + " --pose-b \"1 0 0 1 0 0\"", "expected 7 numbers"},
      {"query " + box + " " + box + " --pose-b \"1 0 0 x 0 0 0\"", "not a finite number"},
      {"query " + box + " " + box + " --pose-b \"1 0 0 0 0 0 0\"", "quaternion"},
      {"query " + box + " " + box + " --mode sometimes", "unknown mode"},
      {"query " + box + " " + box + " --backend warp", "unknown backend 'warp'"},
      {"query " + box + " " + box + " --displacement-threshold 0.5 --distance-extension 0.1", "must not exceed"},
      {"query " + box + " " + box + " --max-walk-steps 0", "max_walk_steps"},
      {"query " + box + " " + box + " --sequence " + bad_json, "not valid JSON"},
      {"query " + box + " " + box + " --sequence " + short_pose, "expected 7 numbers"},
      {"query " + box + " sphere:-1", "radius"},
      {"query " + box + " box:1,2", "box:HX,HY,HZ"},
      {"query " + box + " " + box + " --frobnicate", "frobnicate"},
      {"query " + box, "B"},
      {"", "subcommand"},
  };
  for (const auto& [args, fragment] : cases) {
    const Outcome r = run(args);
    EXPECT_EQ(r.code, 2) << args << "\n" << r.out;
    EXPECT_NE(r.out.find(fragment), std::string::npos) << args << "\n" << r.out;
    EXPECT_EQ(std::count(r.out.begin(), r.out.end(), '\n'), 1) << args << "\n" << r.out;
  }
}

}  // namespace

namespace {

const std::string defects = std::string(RTCD_DATA_DIR) + "/defects/";

TEST(CliCheck, ExitCodesFitDefectUnreadable) {
  const Outcome fit = run("check " + data + "blob_902.obj");
  EXPECT_EQ(fit.code, 0) << fit.out;
  EXPECT_NE(fit.out.find("fit for the method"), std::string::npos) << fit.out;
  // A fit mesh's distance bound: its grid, what it holds, what it took.
  EXPECT_NE(fit.out.find("  distance bound: "), std::string::npos) << fit.out;
  const auto j = nlohmann::json::parse(run("check --json " + data + "blob_902.obj").out);
  ASSERT_TRUE(j[0].contains("distance_bound")) << j.dump();
  const auto& bound = j[0]["distance_bound"];
  size_t nodes = 1;
  for (int n : bound["nodes"]) nodes *= size_t(n);
  EXPECT_GE(nodes, rtcd::DistanceBound::kMinNodes);
  EXPECT_LE(nodes, rtcd::DistanceBound::kMaxNodes);
  EXPECT_EQ(bound["bytes"].get<size_t>(), nodes * sizeof(float));
  EXPECT_GT(bound["cell"].get<double>(), 0.0);
  const Outcome crossing = run("check " + defects + "two_cubes_overlapping.off");
  EXPECT_EQ(crossing.code, 1) << crossing.out;
  EXPECT_NE(crossing.out.find("self_intersections: 6 triangle pairs"), std::string::npos) << crossing.out;
  const Outcome missing = run("check " + data + "blob_902.obj " + defects + "nope.off");
  EXPECT_EQ(missing.code, 2) << missing.out;
  EXPECT_NE(missing.out.find("nope.off: no such file"), std::string::npos) << missing.out;
}

TEST(CliCheck, JsonListsEveryFindingPerFile) {
  const Outcome r = run("check --json " + defects + "flipped_triangle.off " + defects + "pinch_split.off");
  ASSERT_EQ(r.code, 1) << r.out;
  const auto j = nlohmann::json::parse(r.out);
  ASSERT_EQ(j.size(), 2u);
  EXPECT_FALSE(j[0]["fit"].get<bool>());
  EXPECT_EQ(j[0]["findings"]["inconsistent_orientation"]["count"], 3);
  EXPECT_TRUE(j[0]["findings"]["inconsistent_orientation"]["defect"].get<bool>());
  EXPECT_TRUE(j[1]["fit"].get<bool>());
  EXPECT_EQ(j[1]["findings"]["coincident_vertices"]["examples"][0], nlohmann::json({0, 4}));
  // Welded, the two vertices at the pinch become one vertex joining two fans.
  const Outcome welded = run("check --json --weld " + defects + "pinch_split.off");
  ASSERT_EQ(welded.code, 0) << welded.out;
  const auto w = nlohmann::json::parse(welded.out);
  EXPECT_EQ(w[0]["vertices"], 7);
  EXPECT_EQ(w[0]["findings"]["pinch_vertices"]["count"], 1);
}

TEST(CliQuery, WarnsOnceWhenABodyCrossesItself) {
  const Outcome r = run("query " + defects + "two_cubes_overlapping.off box:0.1,0.1,0.1");
  ASSERT_EQ(r.code, 0) << r.out;
  const size_t first = r.out.find("crosses itself");
  ASSERT_NE(first, std::string::npos) << r.out;
  EXPECT_EQ(r.out.find("crosses itself", first + 1), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("2x17"), std::string::npos) << r.out;
}

TEST(CliQuery, WeldIsExplicit) {
  // A box at the pinch of two tetrahedra: each has its own vertex there, each
  // casts a ray; welded, their normals cancel and neither casts.
  auto vertices_of_a = [](const Outcome& r) {
    std::set<int> v;
    const auto j = nlohmann::json::parse(r.out);
    for (const auto& c : j["contacts"])
      if (c["source"] == "a") v.insert(c["vertex"].get<int>());
    return v;
  };
  const Outcome split = run("query " + defects + "pinch_split.off box:0.1,0.1,0.1 --json");
  ASSERT_EQ(split.code, 0) << split.out;
  EXPECT_EQ(vertices_of_a(split), (std::set<int>{0, 4}));
  const Outcome welded = run("query " + defects + "pinch_split.off box:0.1,0.1,0.1 --weld --json");
  ASSERT_EQ(welded.code, 0) << welded.out;
  EXPECT_TRUE(vertices_of_a(welded).empty());
}

TEST(CliQuery, SizesOutsideTheSupportedRangeAreRefused) {
  const Outcome mesh = run("query " + defects + "huge_cube.off box:0.5,0.5,0.5");
  EXPECT_EQ(mesh.code, 2) << mesh.out;
  EXPECT_NE(mesh.out.find("supported coordinate range"), std::string::npos) << mesh.out;
  const Outcome box = run("query box:0.5,0.5,0.5 box:1e13,1e13,1e13");
  EXPECT_EQ(box.code, 2) << box.out;
  EXPECT_NE(box.out.find("outside the supported sizes"), std::string::npos) << box.out;
}

}  // namespace

namespace {

// Meshes and bodies of an imported glTF: nodes that draw a mesh, and the
// triangles of every mesh.
size_t drawn_nodes(const aiNode* n) {
  size_t count = n->mNumMeshes > 0;
  for (unsigned c = 0; c < n->mNumChildren; ++c) count += drawn_nodes(n->mChildren[c]);
  return count;
}

// A recorded run as glTF: read back, one drawn node and one animation
// channel per body (the ground too), a keyframe per recorded step, every
// kind's mesh (the sphere and the box tessellated, the ground a square);
// a bad recording or an unwritable path exits 2, names it, writes nothing.
TEST_F(CliFiles, ViewWritesARecordingAsGltf) {
  const std::string recording = (dir_ / "stack.rtcdrec").string(), glb = (dir_ / "stack.glb").string();
  const Outcome ran = run("run " + std::string(RTCD_DATA_DIR) + "/scenes/stack.json --steps 20 --no-plots --record " +
                          recording + " --out " + (dir_ / "run").string());
  ASSERT_EQ(ran.code, 0) << ran.out;
  const Outcome viewed = run("view " + recording + " --gltf " + glb);
  ASSERT_EQ(viewed.code, 0) << viewed.out;
  EXPECT_NE(viewed.out.find(": 13 bodies, 6 meshes ("), std::string::npos) << viewed.out;
  EXPECT_NE(viewed.out.find(" 20 keyframes of "), std::string::npos) << viewed.out;
  Assimp::Importer importer;
  const aiScene* scene = importer.ReadFile(glb, 0);
  ASSERT_NE(scene, nullptr) << importer.GetErrorString();
  EXPECT_EQ(drawn_nodes(scene->mRootNode), 13u);
  ASSERT_EQ(scene->mNumMeshes, 6u);
  size_t triangles = 0;
  for (unsigned m = 0; m < scene->mNumMeshes; ++m) triangles += scene->mMeshes[m]->mNumFaces;
  EXPECT_NE(viewed.out.find(std::to_string(triangles).append(" triangles)")), std::string::npos) << viewed.out;
  ASSERT_EQ(scene->mNumAnimations, 1u);
  ASSERT_EQ(scene->mAnimations[0]->mNumChannels, 13u);
  for (unsigned c = 0; c < 13; ++c) {
    EXPECT_EQ(scene->mAnimations[0]->mChannels[c]->mNumPositionKeys, 20u) << c;
    EXPECT_EQ(scene->mAnimations[0]->mChannels[c]->mNumRotationKeys, 20u) << c;
  }
  // The blobs fall: a blob's first and last keyframes differ in height.
  const aiNodeAnim* blob = nullptr;
  for (unsigned c = 0; c < 13; ++c)
    if (std::string(scene->mAnimations[0]->mChannels[c]->mNodeName.C_Str()).find(": blob") != std::string::npos)
      blob = scene->mAnimations[0]->mChannels[c];
  ASSERT_NE(blob, nullptr);
  EXPECT_LT(blob->mPositionKeys[19].mValue.z, blob->mPositionKeys[0].mValue.z - 0.01f);

  const std::string junk = write("junk.rtcdrec", "RTCDREC1 and then nothing sensible");
  const std::string nowhere = (dir_ / "no_such_folder" / "x.glb").string();
  for (const auto& [args, fragment, file] : std::vector<std::tuple<std::string, std::string, std::string>>{
           {"view " + junk + " --gltf " + (dir_ / "junk.glb").string(), "junk.rtcdrec", (dir_ / "junk.glb").string()},
           {"view " + recording + " --gltf " + nowhere, "no_such_folder", nowhere},
           {"view " + (dir_ / "run").string(), "recording.rtcdrec", (dir_ / "run" / "view").string()}}) {
    const Outcome r = run(args);
    EXPECT_EQ(r.code, 2) << args << ": " << r.out;
    EXPECT_NE(r.out.find(fragment), std::string::npos) << args << ": " << r.out;
    if (!file.empty()) {
      EXPECT_FALSE(std::filesystem::exists(file)) << file;
    }
  }
}

// `rtcd run --view` records the run and writes its page; `rtcd view
// RUN_DIR` writes it again elsewhere. The page's data: every body posed at
// every step, the kinds' looks once, the replayed contacts. A folder that
// is not a page is never replaced.
TEST_F(CliFiles, ViewWritesARunsPage) {
  const std::filesystem::path run_dir = dir_ / "run";
  const Outcome ran = run("run " + std::string(RTCD_DATA_DIR) + "/scenes/stack.json --steps 20 --no-plots --view --out " +
                          run_dir.string());
  ASSERT_EQ(ran.code, 0) << ran.out;
  ASSERT_TRUE(std::filesystem::exists(run_dir / "recording.rtcdrec"));
  const auto data = [](const std::filesystem::path& page, const std::string& script) {
    std::ifstream in(page / "data" / script);
    std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    const size_t eq = text.find(" = ");
    EXPECT_NE(eq, std::string::npos) << script;
    return nlohmann::json::parse(text.substr(eq + 3, text.rfind(';') - eq - 3));
  };
  for (const std::filesystem::path& page : {run_dir / "view", dir_ / "again"}) {
    if (page != run_dir / "view") {
      const Outcome again = run("view " + run_dir.string() + " --out " + page.string());
      ASSERT_EQ(again.code, 0) << again.out;
      EXPECT_NE(again.out.find("open file://"), std::string::npos) << again.out;
    }
    SCOPED_TRACE(page.string());
    for (const char* file : {"index.html", "viewer.js", "three.min.js", "OrbitControls.js", "data/scene.js",
                             "data/poses.js", "data/contacts.js"})
      EXPECT_GT(std::filesystem::file_size(page / file), 100u) << file;
    const auto scene = data(page, "scene.js");
    EXPECT_EQ(scene["steps"], 20);
    EXPECT_EQ(scene["body_look"].size(), 13u);
    EXPECT_EQ(scene["looks"].size(), 6u);  // five kinds and the ground
    EXPECT_EQ(scene["figures"]["pairs"].size(), 20u);
    // 7 floats a body and step, base64 in lines of 72 characters.
    std::string poses = data(page, "poses.js").get<std::string>();
    std::erase(poses, '\n');
    EXPECT_EQ(poses.size(), (20 * 13 * 7 * 4 + 2) / 3 * 4);
    const auto contacts = data(page, "contacts.js");
    ASSERT_TRUE(contacts.is_object());
    std::string depths = contacts["depths"].get<std::string>();
    std::erase(depths, '\n');
    EXPECT_GT(depths.size(), 100u) << "the blobs touch";
  }
  // Not a page: left as it was.
  std::filesystem::create_directories(dir_ / "mine");
  write("mine/notes.txt", "mine");
  const Outcome refused = run("view " + run_dir.string() + " --out " + (dir_ / "mine").string());
  EXPECT_EQ(refused.code, 2) << refused.out;
  EXPECT_NE(refused.out.find("is not a page"), std::string::npos) << refused.out;
  EXPECT_TRUE(std::filesystem::exists(dir_ / "mine" / "notes.txt"));
  EXPECT_FALSE(std::filesystem::exists(dir_ / "mine" / "index.html"));
  const Outcome missing = run("view " + (dir_ / "nothing_here").string());
  EXPECT_EQ(missing.code, 2) << missing.out;
  EXPECT_NE(missing.out.find("nothing_here"), std::string::npos) << missing.out;
}

// The first second of the small stream through the whole bench, then its
// recording replayed; bad bench inputs exit 2 with one line.
TEST_F(CliFiles, BenchRunsTheSmallStreamAndReplaysItsRecording) {
  const std::string out = (dir_ / "bench").string();
  const Outcome r = run("bench stream_small --steps 60 --seeds 1 --gimpact-host-steps 20 --no-plots --out " + out);
  ASSERT_EQ(r.code, 0) << r.out;
  EXPECT_NE(r.out.find("report: "), std::string::npos) << r.out;
  std::ifstream report(out + "/report.md");
  std::stringstream text;
  text << report.rdbuf();
  EXPECT_NE(text.str().find("stream_small.json"), std::string::npos);
  EXPECT_NE(text.str().find("| auto embree |"), std::string::npos);
  const std::string again = (dir_ / "again").string();
  const Outcome replayed =
      run("bench --replay " + out + "/recording.rtcdrec --seeds 1 --gimpact-host-steps 5 --no-plots --out " + again);
  ASSERT_EQ(replayed.code, 0) << replayed.out;
  EXPECT_TRUE(std::filesystem::exists(again + "/table_2_1.csv"));

  // One configuration on the recording: every pair traced in full in full
  // mode, none of them sent back by equation 2.1, the judged steps counted.
  const std::string recording = out + "/recording.rtcdrec";
  const Outcome full = run("replay " + recording + " --mode full --threads 2 --judge-every 10");
  ASSERT_EQ(full.code, 0) << full.out;
  const size_t all = full.out.find("| all | 60 |");
  ASSERT_NE(all, std::string::npos) << full.out;
  EXPECT_NE(full.out.find("| 100.0% | 0.0% |", all), std::string::npos) << full.out;
  EXPECT_NE(full.out.find("| 6: ", all), std::string::npos) << full.out;
  // Judged whole: no interpenetrating pair called separate, no contact over
  // its true penetration, and contacts were judged.
  const size_t verdict = full.out.find(" pairs missed; ", all);
  ASSERT_NE(verdict, std::string::npos) << full.out;
  EXPECT_EQ(full.out.compare(verdict - 3, 3, "; 0"), 0) << full.out;
  const std::string over = full.out.substr(verdict + 15, full.out.find(" contacts over", verdict) - verdict - 15);
  EXPECT_EQ(over.rfind("0 of ", 0), 0u) << full.out;
  EXPECT_NE(over, "0 of 0") << full.out;
  // The step's counters per phase: full mode traces, never walks.
  EXPECT_NE(full.out.find("| rays_iterative | 0 |"), std::string::npos) << full.out;
  EXPECT_EQ(full.out.find("| rays_full | 0 |"), std::string::npos) << full.out;
  EXPECT_NE(full.out.find("| edges_tested |"), std::string::npos) << full.out;
  // Automatic mode with a small threshold: equation 2.1 sends pairs back,
  // never more than are traced in full.
  const Outcome automatic = run("replay " + recording + " --displacement-threshold 0.01");
  ASSERT_EQ(automatic.code, 0) << automatic.out;
  EXPECT_NE(automatic.out.find("mode auto, 1 thread;"), std::string::npos) << automatic.out;
  // The cells of a replay's "all" row: 2 detect, 8 pairs, 12 contacts.
  auto all_row = [](const std::string& out) {
    std::vector<std::string> cells;
    const size_t row = out.find("| all | 60 |");
    if (row == std::string::npos) return cells;
    std::stringstream line(out.substr(row + 1, out.find('\n', row) - row - 1));
    for (std::string cell; std::getline(line, cell, '|');) cells.push_back(cell);
    return cells;
  };
  const std::vector<std::string> cells = all_row(automatic.out);
  ASSERT_GE(cells.size(), 13u) << automatic.out;
  const double traced_in_full = std::stod(cells[9]), sent_back = std::stod(cells[10]);
  EXPECT_GT(sent_back, 0.0) << automatic.out;
  EXPECT_LE(sent_back, traced_in_full) << automatic.out;
  // The recording's last steps summed apart (a stream has no settled
  // phase): a row of exactly that many steps, before the whole.
  const Outcome tail = run("replay " + recording + " --last 7");
  ASSERT_EQ(tail.code, 0) << tail.out;
  const size_t last = tail.out.find("| last 7 | 7 |");
  ASSERT_NE(last, std::string::npos) << tail.out;
  EXPECT_LT(last, tail.out.find("| all | 60 |")) << tail.out;
  EXPECT_NE(tail.out.find("| counter (per step) | A | B | last 7 | all |"), std::string::npos) << tail.out;
  // A peer on the same steps: the same pairs a step as rtcd, contacts of
  // its own, no stages or rays of ours.
  const Outcome gimpact = run("replay " + recording + " --peer gimpact");
  ASSERT_EQ(gimpact.code, 0) << gimpact.out;
  EXPECT_NE(gimpact.out.find("GIMPACT (bullet-gimpact), one thread"), std::string::npos) << gimpact.out;
  const size_t peer_all = gimpact.out.find("| all | 60 |");
  ASSERT_NE(peer_all, std::string::npos) << gimpact.out;
  EXPECT_NE(gimpact.out.find("| – | – | – | – | " + cells[8].substr(1, cells[8].size() - 2) + " | – |", peer_all),
            std::string::npos)
      << gimpact.out << "\n" << automatic.out;
  EXPECT_EQ(gimpact.out.find("counter (per step)"), std::string::npos) << gimpact.out;
  const Outcome fcl = run("replay " + recording + " --peer fcl --last 7");
  ASSERT_EQ(fcl.code, 0) << fcl.out;
  EXPECT_NE(fcl.out.find("FCL (fcl), one thread"), std::string::npos) << fcl.out;
  EXPECT_NE(fcl.out.find("| last 7 | 7 |"), std::string::npos) << fcl.out;
  // Each peer ran: time spent and contacts found, FCL's count its own
  // (GIMPACT, like rtcd, counts the vertices under the ground here).
  const std::vector<std::string> by_gimpact = all_row(gimpact.out), by_fcl = all_row(fcl.out);
  ASSERT_GE(by_gimpact.size(), 13u) << gimpact.out;
  ASSERT_GE(by_fcl.size(), 13u) << fcl.out;
  for (const auto* peer : {&by_gimpact, &by_fcl}) {
    EXPECT_GT(std::stod((*peer)[2]), 0.0) << "detect";
    EXPECT_GT(std::stod((*peer)[12]), 0.0) << "contacts";
  }
  EXPECT_NE(std::stod(by_fcl[12]), std::stod(by_gimpact[12]));
  EXPECT_NE(std::stod(by_fcl[12]), std::stod(cells[12]));

  const std::string junk = write("junk.rtcdrec", "RTCDREC1 and then nothing sensible");
  for (const auto& [args, fragment] : std::vector<std::pair<std::string, std::string>>{
           {"bench no_such_scene", "no such scene file"},
           {"bench", "give a SCENE"},
           {"bench avalanche --replay " + junk, "not both"},
           {"bench --replay " + junk, "junk.rtcdrec"},
           {"bench avalanche --seeds 0", "seeds"},
           {"bench avalanche --steps 0", "steps"},
           {"replay " + junk, "junk.rtcdrec"},
           {"replay " + out + "/recording.rtcdrec --mode sideways", "sideways"},
           {"replay " + out + "/recording.rtcdrec --backend nosuch", "nosuch"},
           {"replay " + out + "/recording.rtcdrec --last 61", "holds only 60 steps"},
           {"replay " + out + "/recording.rtcdrec --peer bullet", "gimpact or fcl"},
           {"replay " + out + "/recording.rtcdrec --peer fcl --mode full", "excludes"},
           {"replay " + out + "/recording.rtcdrec --peer gimpact --no-edge-contacts", "knobs are rtcd's"},
           {"replay " + out + "/recording.rtcdrec --peer gimpact --judge-every 5", "knobs are rtcd's"}}) {
    const Outcome bad = run(args);
    EXPECT_EQ(bad.code, 2) << args << "\n" << bad.out;
    EXPECT_NE(bad.out.find(fragment), std::string::npos) << args << "\n" << bad.out;
    EXPECT_EQ(std::count(bad.out.begin(), bad.out.end(), '\n'), 1) << args << "\n" << bad.out;
  }
}

}  // namespace
