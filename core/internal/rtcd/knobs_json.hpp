// The knobs of a configuration as JSON, by the table (config.hpp): what
// `rtcd run` and `rtcd validate` print. Header-only, for the tools that
// already use nlohmann-json.
#pragma once

#include <nlohmann/json.hpp>

#include "rtcd/config.hpp"

namespace rtcd {

// Numbers as numbers, an unset limit as "derived", switches as booleans,
// the mode as its name.
inline nlohmann::json knobs_json(const Config& config) {
  nlohmann::json j = nlohmann::json::object();
  for (const Knob& k : knobs()) {
    const KnobValue v = k.get(config);
    if (std::holds_alternative<std::monostate>(v)) j[k.name] = "derived";
    else if (const bool* b = std::get_if<bool>(&v)) j[k.name] = *b;
    else if (const double* d = std::get_if<double>(&v)) j[k.name] = *d;
    else j[k.name] = to_string(std::get<Mode>(v));
  }
  return j;
}

}  // namespace rtcd
