// `rtcd validate`: differential runs against the oracles, printed per
// family, mode and backend; with --sweep, the accuracy/time sweep as CSV.
// Across the ranks of an MPI job, each rank runs its share of every run's
// pairs and rank 0 reports what one process would (the seconds aside); with
// a campaign directory, every finished shard of pairs is kept there, and a
// campaign started again with the same directory runs only what it lacks.
#pragma once

#include <cstdint>
#include <string>

#include <nlohmann/json.hpp>

#include "rtcd/app/inputs.hpp"
#include "rtcd/app/ranks.hpp"

namespace rtcd::app {

struct ValidateOptions {
  std::string backend;  // empty: every usable backend
  std::string family;   // empty: every family
  std::string mode = "full";
  size_t pairs = 1000;
  uint64_t seed = 1;
  bool json = false;
  bool no_oracles = false;
  Knobs knobs;
  std::string sweep_csv;  // with --sweep: where the CSV goes ("-" for standard output)
  std::string campaign;   // the campaign's directory; empty: none
  size_t shard_pairs = 100;  // a campaign's pairs per shard
  double hours = 0.0;        // a campaign stops after the shard in flight past this; 0: no limit
};

// The exit code of a campaign stopped by its hours with shards left to run.
inline constexpr int kCampaignUnfinished = 3;

int run_validate(const ValidateOptions& options, const Ranks& ranks = one_process());

// The differential runs of `options` (families × backends; not the sweep),
// each summary as `rtcd validate --json` prints it.
nlohmann::json validate_json(const ValidateOptions& options);

}  // namespace rtcd::app
