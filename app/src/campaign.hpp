// A validation campaign's directory: the arguments and commit it was made
// with (campaign.json), and each finished shard of pairs in a file of its
// own, written atomically, so a campaign killed at any moment loses at most
// the shards in flight and its next start runs only those it lacks.
#pragma once

#include <chrono>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "rtcd/app/ranks.hpp"
#include "rtcd/validation/differential.hpp"

namespace rtcd::app {

class Campaign {
 public:
  // Makes `dir` a campaign of `arguments` (rank 0), or opens the one there:
  // one made with other arguments or by another commit, or a directory that
  // is not a campaign and not empty, is refused with a UsageError naming it.
  Campaign(std::filesystem::path dir, nlohmann::json arguments, size_t shard_pairs, double hours,
           const Ranks& ranks);

  size_t shard_pairs() const { return shard_pairs_; }
  // The shards of run `run` (family.backend.mode) not in the directory yet.
  std::vector<size_t> missing(const std::string& run, size_t shards) const;
  // Shard `k` of `run` as it was kept; a file that is not a whole shard of
  // this campaign is refused with a UsageError naming it.
  validation::Shard load(const std::string& run, size_t k, size_t first, size_t count) const;
  void store(const std::string& run, size_t k, const validation::Shard& shard);
  // Past its hours: no further shard starts.
  bool out_of_time() const;
  void write_report(const nlohmann::json& report) const;
  const std::filesystem::path& dir() const { return dir_; }

 private:
  std::filesystem::path shard_path(const std::string& run, size_t k) const;

  std::filesystem::path dir_;
  nlohmann::json identity_;  // arguments and commit
  size_t shard_pairs_;
  double hours_;
  std::chrono::steady_clock::time_point start_ = std::chrono::steady_clock::now();
  size_t stored_ = 0;  // by this process, for the test hook
};

// Spreads a run's shards over the ranks (shard k of the missing ones on rank
// k mod size) and gathers them on rank 0; with a campaign, the cut is the
// campaign's, each shard is kept in its directory as it is done, and rank 0
// reads them all back (nothing when some are missing: stopped by its hours).
class SpreadShards : public validation::ShardRunner {
 public:
  SpreadShards(const Ranks& ranks, Campaign* campaign) : ranks(ranks), campaign(campaign) {}
  std::optional<std::vector<validation::Shard>> run(const validation::Family& family,
                                                    const validation::RunOptions& options) const override;
  bool unfinished() const { return unfinished_; }

 private:
  std::optional<std::vector<validation::Shard>> run_in_campaign(const validation::Family& family,
                                                                const validation::RunOptions& options) const;
  const Ranks& ranks;
  Campaign* campaign;
  mutable bool unfinished_ = false;
};

// The run's name in a campaign: family.backend.mode, the backend by kind
// (ranks may place theirs on different devices).
std::string run_name(const validation::Family& family, const validation::RunOptions& options);

}  // namespace rtcd::app
