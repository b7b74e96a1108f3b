// `rtcd validate --json` run as a user would, for the campaign and MPI suites.
#pragma once

#include <string>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "command.hpp"

namespace rtcd::test {

// Everything `rtcd validate --json` reports but the seconds.
inline nlohmann::json without_seconds(nlohmann::json runs) {
  for (auto& run : runs) run.erase("seconds_per_pair");
  return runs;
}

// `output`, when given, receives the whole output (stdout and stderr).
inline nlohmann::json validate_json(const std::string& args, const std::string& prefix = "",
                                    std::string* output = nullptr) {
  const Outcome r = run_command("validate " + args + " --json", prefix);
  if (output) *output = r.out;
  EXPECT_EQ(r.code, 0) << r.out;
  // stdout and stderr share the pipe (mpirun's notes, warnings): the JSON
  // is the array printed whole.
  const auto start = r.out.find("[\n"), end = r.out.rfind("\n]");
  if (r.code != 0 || start == std::string::npos || end == std::string::npos) return nlohmann::json::array();
  return without_seconds(nlohmann::json::parse(r.out.substr(start, end + 2 - start)));
}

// The campaigns' run: a concave family, few pairs.
inline const std::string kRun = "--family concave --backend embree --pairs 23 --seed 7";

}  // namespace rtcd::test
