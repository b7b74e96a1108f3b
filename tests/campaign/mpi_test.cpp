// `mpirun -n N rtcd validate` for N = 1, 2, 3: every count, rate and bound
// in the JSON (and the sweep's CSV) equals the one-process run's, with and
// without a campaign, and a campaign whose ranks all died resumes on
// another number of ranks.
#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <map>
#include <sstream>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "validate_json.hpp"

namespace {

namespace fs = std::filesystem;
using rtcd::test::kRun;
using rtcd::test::Outcome;
using rtcd::test::run_command;
using rtcd::test::validate_json;

// mpirun as root, more ranks than cores.
std::string mpirun(int ranks) {
  return std::string("OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 ") + RTCD_MPIEXEC + " -n " +
         std::to_string(ranks) + " --oversubscribe ";
}

class Ranks : public ::testing::TestWithParam<int> {};

TEST_P(Ranks, ReportWhatOneProcessDoes) {
  for (const std::string family : {"convex", "concave"})
    for (const std::string mode : {"full", "iterative"}) {
      const std::string args = "--family " + family + " --backend embree --pairs 23 --seed 3 --mode " + mode;
      const nlohmann::json one = validate_json(args);
      ASSERT_EQ(one.size(), 1u);
      EXPECT_GT(one[0]["deep_origins"].get<size_t>(), 0u);
      EXPECT_EQ(validate_json(args, mpirun(GetParam())), one) << family << ' ' << mode;
    }
}

// The sweep's CSV less its seconds column (the eighth).
std::string sweep_without_seconds(const std::string& prefix) {
  const Outcome r = run_command("validate --sweep --family convex --backend embree --pairs 20", prefix);
  EXPECT_EQ(r.code, 0) << r.out;
  std::istringstream in(r.out);
  std::string kept;
  for (std::string line; std::getline(in, line);) {
    if (line.find(',') == std::string::npos) continue;  // mpirun's notes
    std::istringstream fields(line);
    std::string field;
    for (int i = 1; std::getline(fields, field, ','); ++i)
      if (i != 8) kept += field + ',';
    kept += '\n';
  }
  return kept;
}

TEST_P(Ranks, SweepReportsWhatOneProcessDoes) {
  const std::string one = sweep_without_seconds("");
  EXPECT_GT(std::count(one.begin(), one.end(), '\n'), 10);
  EXPECT_EQ(sweep_without_seconds(mpirun(GetParam())), one);
}

TEST_P(Ranks, ResumeACampaignThatLostARank) {
  const fs::path dir = fs::temp_directory_path() / ("rtcd_mpi_campaign_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  const std::string args = kRun + " --mode full --no-oracles --campaign " + dir.string() + " --shard-pairs 3";
  // Every rank dies after its first shard: the job is lost, killed (not
  // failing to start), with the shards finished before the kill kept.
  const Outcome r = run_command("validate " + args, "RTCD_CAMPAIGN_KILL=after:1 " + mpirun(GetParam()));
  EXPECT_NE(r.code, 0) << r.out;
  EXPECT_NE(r.out.find("signal 9"), std::string::npos) << "not killed: " << r.out;
  std::map<fs::path, fs::file_time_type> kept;
  for (const auto& e : fs::directory_iterator(dir / "runs" / "concave.embree.full"))
    if (e.path().extension() == ".json") kept[e.path()] = fs::last_write_time(e.path());
  ASSERT_GE(kept.size(), 1u);
  ASSERT_LE(kept.size(), size_t(GetParam()));
  // Resumed on another number of ranks: the kept shards read back, not run
  // again (untouched, and counted as kept), the rest run, the same report.
  std::string out;
  EXPECT_EQ(validate_json(args, mpirun(GetParam() % 3 + 1), &out), validate_json(kRun + " --mode full --no-oracles"));
  const std::string reused = std::to_string(kept.size()) + " of 8 shards kept from before, " +
                             std::to_string(8 - kept.size()) + " run now";  // 23 pairs in shards of 3
  EXPECT_NE(out.find(reused), std::string::npos) << "expected '" << reused << "': " << out;
  for (const auto& [path, written] : kept) EXPECT_EQ(fs::last_write_time(path), written) << path << " ran again";
  fs::remove_all(dir);
}

// A rank with other arguments (pairs by rank) would wait for runs the others
// never make: the job ends, naming the difference.
TEST(MpiRanks, OtherArgumentsOnARankEndTheJob) {
  const Outcome r = run_command(
      "validate --family convex --backend embree --no-oracles --pairs $((10 + OMPI_COMM_WORLD_RANK))'",
      mpirun(2) + "sh -c 'exec ");
  EXPECT_EQ(r.code, 2) << r.out;
  EXPECT_NE(r.out.find("give every rank the same arguments"), std::string::npos) << r.out;
}

INSTANTIATE_TEST_SUITE_P(Mpi, Ranks, ::testing::Values(1, 2, 3));

}  // namespace
