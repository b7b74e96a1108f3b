// The accuracy knobs as command-line options: one per entry of
// rtcd::knobs() (the mode excepted: each command has its own --mode),
// --NAME for numbers, --no-NAME for switches that default on.
#pragma once

#include <CLI/CLI.hpp>

#include "rtcd/app/inputs.hpp"

namespace rtcd::cli {

void add_knobs(CLI::App& command, app::Knobs& knobs);

}  // namespace rtcd::cli
