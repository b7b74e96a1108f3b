// The accuracy/time knobs of the narrow phase, and their one table: the
// configuration is validated from it, and the CLI options, the scene keys,
// the JSON output and docs/knobs.md are made from it.
#pragma once

#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <variant>

#include "rtcd/export.hpp"

namespace rtcd {
RTCD_PUBLIC_BEGIN

enum class Mode {
  full,       // trace every candidate ray every step (no pair state is used)
  iterative,  // after a pair's first full step, always walk from last step's triangles
  automatic,  // iterative while equation 2.1 stays under displacement_threshold, else full
};

const char* to_string(Mode mode);
Mode parse_mode(const std::string& text);  // "full" | "iterative" | "auto"; ConfigError otherwise

// Each field is a knob: its meaning, range, default and cost are in the knob
// table (knobs(), core/src/config.cpp; docs/knobs.md), said once there.
struct Config {
  // Left empty, each limit is derived per pair and step from the two shapes'
  // sizes, thickness and triangles and the pair's motion (docs/knobs.md
  // gives the rules); a value set here applies to every pair.
  std::optional<uint32_t> max_walk_steps;
  std::optional<double> displacement_threshold;  // at most distance_extension
  std::optional<double> distance_extension;

  bool predictive = true;
  bool verify_walks = true;
  bool edge_contacts = true;     // Contact::edge, ContactKind::edge
  bool edges_beside_contacts = true;  // off: walking steps rest edges while the pair has vertex contacts
  bool edges_both_sides = true;       // off: a pair of meshes tests the finer mesh's edges only
  std::optional<double> edge_retest_motion;  // walking steps; unset: every watched edge every step
  bool trace_separated_pairs = true;  // off: pairs proven apart cast nothing until they move past the proof
  bool nearest_surface = true;   // off: the thesis' ray contact
  bool projected = true;         // what Contact::push holds for ray contacts
  Mode mode = Mode::automatic;

  // Throws ConfigError naming the knob and its allowed range (knobs()),
  // or the two knobs that contradict each other.
  void validate() const;
};

// A knob's value as the table reads and writes it: unset (derived per
// pair), a switch, a number, or the mode.
using KnobValue = std::variant<std::monostate, bool, double, Mode>;

enum class KnobType : uint8_t {
  flag,    // on or off
  count,   // a whole number in [min, max], or unset: derived per pair
  length,  // a length in [min, max], or unset: derived per pair
  mode,    // full, iterative or auto
};

struct Knob {
  const char* name;  // the Config field, the scene's narrow_phase key, the JSON key
  KnobType type;
  double min, max;      // count, length: the closed range of a value set
  const char* unset;    // the default, in words ("derived per pair", "on", "auto")
  const char* meaning;  // one line
  const char* cost;     // one line
  const char* off;      // switches: what turning it off does, one line; nullptr for the others
  // Set by the scene's effects list instead of a narrow_phase key (the one
  // place that turns it on): predictive, projected.
  bool effect;
  KnobValue (*get)(const Config&);
  // Throws ConfigError for a value of the wrong kind; ranges are
  // Config::validate's.
  void (*set)(Config&, const KnobValue&);
};

// Every knob, in Config's order.
std::span<const Knob> knobs();
// nullptr for a name not in the table.
const Knob* find_knob(std::string_view name);
// "derived per pair", "on", "off", "0.05", "auto".
std::string to_string(const KnobValue& value);

RTCD_PUBLIC_END
}  // namespace rtcd
