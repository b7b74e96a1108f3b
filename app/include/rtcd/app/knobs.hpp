// `rtcd knobs`: the table of knobs and of the step's ray counters, as
// docs/knobs.md holds it.
#pragma once

#include <ostream>

namespace rtcd::app {

void print_knobs(std::ostream& out);

}  // namespace rtcd::app
