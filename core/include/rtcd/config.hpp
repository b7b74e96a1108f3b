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

struct Config {
  // The three limits below follow the scene unless set: left empty, each is
  // derived per pair and step from the two shapes' sizes, thickness and
  // triangle size and the pair's motion since the last step (rtcd/limits.hpp
  // gives the rules). A value set here applies to every pair.

  // Most triangles one walk visits before it gives up (Algorithm 1's max).
  // Range [1, 1'000'000]. Derived: enough to cross four times the distance a
  // walk may have to cover, at least 32. Cost: linear in the steps walks
  // take; too low loses rays that moved across many triangles.
  std::optional<uint32_t> max_walk_steps;

  // Relative motion (equation 2.1, in length units) since a pair's last full
  // step above which the pair is traced in full again. Range [0,
  // distance_extension]. Derived: half the extension, at most a quarter of
  // the thinner body's thickness.
  // Cost: higher keeps pairs iterative longer (cheaper) but walks lose more
  // rays on concave regions.
  std::optional<double> displacement_threshold;

  // How far outside the other body a vertex is still tracked by a predictive
  // ray, and how much both bounding boxes grow before selecting candidate
  // vertices. Range [0, 1e12], and >= displacement_threshold. Derived: a
  // tenth of the smaller body's radius, or twice the pair's last motion if
  // that is more (at most the radius). Cost: more candidate vertices and longer predictive rays.
  std::optional<double> distance_extension;

  // Cast predictive rays so vertices about to penetrate are tracked by the
  // iterative walk (section 2.1.3). Default on. Cost: one short extra ray per
  // non-penetrating candidate in full steps, one walk per tracked vertex after.
  bool predictive = true;

  // After the walks say a vertex is inside, cast one ray toward the nearer
  // of the two faces they found: a concave target can fold between them,
  // and a vertex that moved out into such a gap would be reported at a
  // stale depth. Default on; skipped against convex meshes. Cost: one ray
  // no longer than that distance per walked contact beyond its face's
  // clearance (fold.h), which most contacts lie within.
  bool verify_walks = true;

  // Test each edge of the source against the target too: two surfaces can
  // cross with no ray origin inside either (planks laid crosswise). An edge
  // whose ends are outside but whose line enters the target gives an edge
  // contact (Contact::edge). Default on. Cost: the edges near a pair's
  // overlap (about three per candidate vertex of a closed mesh) each cast
  // one ray as long as the edge, a second when the first enters the target
  // and two more and a nearest-triangle query for a crossing; in walking
  // modes the edges near the target are tested again every step.
  bool edge_contacts = true;

  // Measure each contact against the target's nearest surface: the ray
  // proves a vertex is inside, and its depth, direction and face are those
  // of the nearest point of the target's surface (the true penetration).
  // Off: the thesis' ray contact, as deep as the ray runs to where it leaves
  // the target (on a thin tube's side, across the tube and out of the far
  // side of what it presses into). Default on. Cost: one nearest-triangle
  // query per vertex contact, within its ray's exit distance.
  bool nearest_surface = true;

  // Ray contacts (nearest_surface off) push along the impacted triangle's
  // normal by the projected depth (section 2.2) rather than along the ray by
  // its depth: what Contact::push holds. A contact measured to the nearest
  // surface pushes along its way out, that surface's normal. Default on.
  // Cost: none here; it changes what the solver receives.
  bool projected = true;

  // Full, iterative or automatic (default).
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
