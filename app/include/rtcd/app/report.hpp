// Printing results: one JSON object per step, or a readable table.
#pragma once

#include <ostream>

#include <nlohmann/json.hpp>

#include "rtcd/results.hpp"

namespace rtcd::app {

// The result of the single pair of a `rtcd query` step.
nlohmann::json to_json(const StepResult& step);
// A step's statistics: every counter, the walks' endings, devices and seconds.
nlohmann::json stats_json(const StepStats& stats);
void print_table(std::ostream& out, const StepResult& step);

}  // namespace rtcd::app
