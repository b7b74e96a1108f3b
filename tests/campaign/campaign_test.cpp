// `rtcd validate` cut into shards: a campaign killed at a shard's boundary
// and inside one (RTCD_CAMPAIGN_KILL, the campaign's test hook) and started
// again reports what an uninterrupted run does; a corrupt shard and a
// directory made with other arguments are refused by name.
#include <unistd.h>

#include <filesystem>
#include <fstream>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "validate_json.hpp"

namespace {

namespace fs = std::filesystem;
using rtcd::test::Outcome;
using rtcd::test::run_command;
using rtcd::test::validate_json;
using rtcd::test::without_seconds;
using rtcd::test::kRun;

class CampaignDir : public ::testing::Test {
 protected:
  void SetUp() override {
    dir = fs::temp_directory_path() /
          ("rtcd_campaign_" + std::to_string(::getpid()) + "_" +
           ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir);
  }
  void TearDown() override { fs::remove_all(dir); }
  std::string campaign(const std::string& extra = "") const {
    return kRun + " --mode iterative --campaign " + dir.string() + " --shard-pairs 5" + extra;
  }
  fs::path shard(size_t k) const {
    return dir / "runs" / "concave.embree.iterative" / ("shard-00000" + std::to_string(k) + ".json");
  }
  size_t shards_kept() const {
    size_t n = 0;
    std::error_code none;
    for (const auto& e : fs::directory_iterator(dir / "runs" / "concave.embree.iterative", none))
      n += e.path().extension() == ".json";
    return n;
  }
  fs::path dir;
};

TEST_F(CampaignDir, KilledAtAShardsBoundaryAndInsideOneResumesToTheSameReport) {
  const nlohmann::json whole = validate_json(kRun + " --mode iterative");
  ASSERT_EQ(whole.size(), 1u);

  Outcome r = run_command("validate " + campaign(), "RTCD_CAMPAIGN_KILL=after:2 ");
  EXPECT_NE(r.code, 0) << r.out;  // killed
  EXPECT_EQ(shards_kept(), 2u);
  r = run_command("validate " + campaign(), "RTCD_CAMPAIGN_KILL=inside:1 ");
  EXPECT_NE(r.code, 0) << r.out;  // killed with shard 4 half written
  EXPECT_EQ(shards_kept(), 3u);
  const auto shard_2_written = fs::last_write_time(shard(2));

  const nlohmann::json resumed = validate_json(campaign());
  EXPECT_EQ(resumed, whole);
  EXPECT_EQ(shards_kept(), 5u);  // 23 pairs in shards of 5
  EXPECT_EQ(fs::last_write_time(shard(2)), shard_2_written) << "a kept shard ran again";
  for (const auto& e : fs::recursive_directory_iterator(dir))
    EXPECT_EQ(e.path().string().find(".tmp"), std::string::npos) << "left behind: " << e.path();

  // Finished: started again, it runs nothing and reports the same.
  EXPECT_EQ(validate_json(campaign()), whole);
  std::ifstream report(dir / "report.json");
  ASSERT_TRUE(report);
  EXPECT_EQ(without_seconds(nlohmann::json::parse(report)["runs"]), whole);
}

TEST_F(CampaignDir, ACorruptShardIsRefusedByName) {
  ASSERT_EQ(run_command("validate " + campaign(" --no-oracles")).code, 0);
  fs::resize_file(shard(3), fs::file_size(shard(3)) / 2);
  const Outcome r = run_command("validate " + campaign(" --no-oracles"));
  EXPECT_EQ(r.code, 2) << r.out;
  EXPECT_NE(r.out.find(shard(3).string()), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("corrupt"), std::string::npos) << r.out;
}

TEST_F(CampaignDir, ADirectoryOfOtherArgumentsOrAnotherBuildIsRefused) {
  ASSERT_EQ(run_command("validate " + campaign(" --no-oracles")).code, 0);
  for (const std::string other : {"", " --no-oracles --no-predictive"}) {
    const Outcome r = run_command("validate " + campaign(other));
    EXPECT_EQ(r.code, 2) << other << ": " << r.out;
    EXPECT_NE(r.out.find(dir.string()), std::string::npos) << r.out;
    EXPECT_NE(r.out.find("other arguments"), std::string::npos) << r.out;
  }
  // Made by another build.
  {
    std::ifstream in(dir / "campaign.json");
    nlohmann::json made = nlohmann::json::parse(in);
    made["commit"] = "0000000000000000000000000000000000000000";
    std::ofstream(dir / "campaign.json") << made.dump(2);
    const Outcome r = run_command("validate " + campaign(" --no-oracles"));
    EXPECT_EQ(r.code, 2) << r.out;
    EXPECT_NE(r.out.find("commit: was \"0000000000000000000000000000000000000000\""), std::string::npos) << r.out;
  }
  // Not a campaign's directory at all.
  fs::remove(dir / "campaign.json");
  const Outcome r = run_command("validate " + campaign(" --no-oracles"));
  EXPECT_EQ(r.code, 2) << r.out;
  EXPECT_NE(r.out.find("not a campaign"), std::string::npos) << r.out;
}

TEST_F(CampaignDir, HoursSpentStartNoShardAndExit3) {
  // A limit already past: no shard starts, exit 3.
  const Outcome r = run_command("validate " + campaign(" --no-oracles --hours 1e-12"));
  EXPECT_EQ(r.code, 3) << r.out;
  EXPECT_EQ(shards_kept(), 0u);
  EXPECT_NE(r.out.find("start it again"), std::string::npos) << r.out;
  EXPECT_EQ(validate_json(campaign(" --no-oracles")), validate_json(kRun + " --mode iterative --no-oracles"));
}

}  // namespace
