// `rtcd validate`: differential runs against the oracles, printed per
// family, mode and backend; with --sweep, the accuracy/time sweep as CSV.
#pragma once

#include <cstdint>
#include <string>

#include <nlohmann/json.hpp>

#include "rtcd/app/inputs.hpp"

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
};

int run_validate(const ValidateOptions& options);

// The differential runs of `options` (families × backends; not the sweep),
// each summary as `rtcd validate --json` prints it.
nlohmann::json validate_json(const ValidateOptions& options);

}  // namespace rtcd::app
