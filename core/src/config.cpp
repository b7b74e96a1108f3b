// The table of knobs, and the configuration's validation from it.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <sstream>

#include "rtcd/config.hpp"
#include "rtcd/error.hpp"

namespace rtcd {
namespace {

// The largest length a knob takes: the coordinates rtcd answers for
// (mesh.hpp) go up to 1e12.
constexpr double kLongest = 1e12;

// 1000000, 0.05, 1e12.
std::string number_text(double v) {
  std::ostringstream s;
  if (std::abs(v) < 1e7 && v == std::floor(v)) s << int64_t(v);
  else s << v;
  std::string text = s.str();
  if (const size_t e = text.find("e+"); e != std::string::npos) text.erase(e + 1, 1);
  return text;
}

[[noreturn]] void wrong_kind(const char* name, const char* wanted) {
  throw ConfigError(std::string(name) + " takes " + wanted);
}

template <class T>
KnobValue optional_value(const std::optional<T>& v) {
  return v ? KnobValue(double(*v)) : KnobValue();
}

// An unset value (monostate) or a number for an optional field.
template <class T>
void set_optional(std::optional<T>& field, const KnobValue& v, const char* name) {
  if (std::holds_alternative<std::monostate>(v)) {
    field.reset();
  } else if (const double* d = std::get_if<double>(&v)) {
    if constexpr (std::is_integral_v<T>) {
      // Ranges are validate()'s to report; a count must at least be one.
      if (!(*d >= 0 && *d <= 4294967295.0 && *d == std::floor(*d)))
        throw ConfigError(std::string(name) + " = " + number_text(*d) + " is not a whole number");
    }
    field = T(*d);
  } else {
    wrong_kind(name, "a number, or nothing (derived per pair)");
  }
}

void set_flag(bool& field, const KnobValue& v, const char* name) {
  if (const bool* b = std::get_if<bool>(&v)) field = *b;
  else wrong_kind(name, "on or off");
}

#define RTCD_OPTIONAL_KNOB(field)                                                           \
  [](const Config& c) { return optional_value(c.field); },                                  \
      [](Config& c, const KnobValue& v) { set_optional(c.field, v, #field); }
#define RTCD_FLAG_KNOB(field)                                            \
  [](const Config& c) { return KnobValue(c.field); },                    \
      [](Config& c, const KnobValue& v) { set_flag(c.field, v, #field); }

const Knob kKnobs[] = {
    {"max_walk_steps", KnobType::count, 1, 1'000'000, "derived per pair",
     "most triangles one walk visits before it gives up (Algorithm 1's max)",
     "linear in the steps walks take; too low loses rays that moved across many triangles", nullptr, false,
     RTCD_OPTIONAL_KNOB(max_walk_steps)},
    {"displacement_threshold", KnobType::length, 0, kLongest, "derived per pair",
     "relative motion since a pair's last full step (equation 2.1) above which it is traced in full again; at most "
     "distance_extension",
     "higher keeps pairs walking longer (cheaper), but walks lose more rays on concave regions", nullptr, false,
     RTCD_OPTIONAL_KNOB(displacement_threshold)},
    {"distance_extension", KnobType::length, 0, kLongest, "derived per pair",
     "how far outside the other body a vertex is still tracked by a predictive ray, and how far bounding boxes grow",
     "more candidate vertices and longer predictive rays", nullptr, false, RTCD_OPTIONAL_KNOB(distance_extension)},
    {"predictive", KnobType::flag, 0, 0, "on",
     "cast predictive rays, so the walk tracks vertices about to penetrate (section 2.1.3)",
     "one short ray per non-penetrating candidate in full steps, one walk per tracked vertex after",
     "No predictive rays: walking steps follow only the vertices found inside, so a vertex that enters while its pair "
     "walks is found at the pair's next full trace",
     true,
     RTCD_FLAG_KNOB(predictive)},
    {"verify_walks", KnobType::flag, 0, 0, "on",
     "check a walked contact for a fold of a concave target between its two faces",
     "one ray per walked contact beyond its face's clearance, which most contacts lie within",
     "Walked contacts are not checked for a fold: a vertex that moved into a gap of a concave target can still read "
     "as inside",
     false,
     RTCD_FLAG_KNOB(verify_walks)},
    {"edge_contacts", KnobType::flag, 0, 0, "on",
     "test the source's edges too: surfaces that cross with no vertex inside (planks laid crosswise)",
     "one to four rays per edge near the overlap, retested each walking step; 2.2x a full step of concave blobs, "
     "2.9x a walking one",
     "Vertex rays only: surfaces that cross with no vertex inside (planks laid crosswise, thin bars) go unseen", false,
     RTCD_FLAG_KNOB(edge_contacts)},
    {"edges_beside_contacts", KnobType::flag, 0, 0, "on",
     "walking steps test the edges of a pair whose vertex rays report contacts too, not only of pairs with none",
     "the edge tests of walking pairs beside their vertex contacts: in the settled avalanche 28% of the edges "
     "tested and a third of the walks' time",
     "Walking steps rest a pair's edges while its vertex rays reported contacts the step before, until they report "
     "none or the pair is traced in full: a crossing beside a contact region goes unseen meanwhile",
     false,
     RTCD_FLAG_KNOB(edges_beside_contacts)},
    {"edges_both_sides", KnobType::flag, 0, 0, "on",
     "a pair of meshes tests the edges of both meshes against the other",
     "the edge tests of the second mesh: in the settled avalanche half the edges tested, a third of its ray time",
     "A pair of meshes tests only the edges of the finer one (the shorter longest edge; the lower body id on a "
     "tie): a crossing with no vertex inside is still found wherever an edge of that mesh crosses, which every "
     "crossing does unless the other mesh passes a part free of vertices (a rod, a thin tip) right through a wall "
     "of the finer one",
     false,
     RTCD_FLAG_KNOB(edges_both_sides)},
    {"edge_retest_motion", KnobType::length, 0, kLongest, "every step",
     "walking steps test a pair's watched edges (those that did not cross) again only once the pair has moved this far "
     "(equation 2.1) since their last test; edges that crossed are tested every step, so no contact is stale, and a "
     "crossing that begins meanwhile is found at most this much motion late",
     "none; larger holds more of a resting pile's edges (their tests are most of its walks), and finds new crossings "
     "later",
     nullptr, false, RTCD_OPTIONAL_KNOB(edge_retest_motion)},
    {"trace_separated_pairs", KnobType::flag, 0, 0, "on",
     "every pair in the broad phase's list casts its rays and tests its edges every step, however far apart its "
     "bodies are",
     "off costs one distance-bound lookup per feature of both bodies near the other's box when a pair is tried; a "
     "walking pair with nothing to report is tried too, and traced in full next step when the bounds pass; in the "
     "settled avalanche the pairs it skips hold 0.3% of the edge tests",
     "A pair traced in full with nothing to report, which the shapes' distance bounds prove apart by more than the "
     "distance extension, casts nothing (PairMode::certified) until its motion (equation 2.1) passes that margin; "
     "then it is traced in full, that same step (not in full mode)",
     false,
     RTCD_FLAG_KNOB(trace_separated_pairs)},
    {"nearest_surface", KnobType::flag, 0, 0, "on",
     "measure each contact's depth and push to the target's nearest surface point, not along its ray to where it "
     "leaves the target",
     "one nearest-triangle query per vertex contact, within its ray's exit distance",
     "Each contact measured along its ray to where it leaves the target (the thesis' ray contact), which overstates "
     "depth on thin or coarse targets",
     false,
     RTCD_FLAG_KNOB(nearest_surface)},
    {"projected", KnobType::flag, 0, 0, "on",
     "ray contacts (nearest_surface off) push along the impacted triangle's normal by the projected depth (section "
     "2.2), not along the ray",
     "none here; it changes what the solver receives",
     "Ray contacts push along their rays by their whole depth, not along the impacted triangle's normal", true,
     RTCD_FLAG_KNOB(projected)},
    {"mode", KnobType::mode, 0, 0, "auto",
     "full: trace every step; iterative: walk after a pair's first full step; auto: walk while equation 2.1 allows",
     "full costs a trace per candidate every step; iterative risks rays lost on large motions", nullptr, false,
     [](const Config& c) { return KnobValue(c.mode); },
     [](Config& c, const KnobValue& v) {
       if (const Mode* m = std::get_if<Mode>(&v)) c.mode = *m;
       else wrong_kind("mode", "full, iterative or auto");
     }},
};

#undef RTCD_OPTIONAL_KNOB
#undef RTCD_FLAG_KNOB

}  // namespace

std::span<const Knob> knobs() { return kKnobs; }

const Knob* find_knob(std::string_view name) {
  for (const Knob& k : kKnobs)
    if (name == k.name) return &k;
  return nullptr;
}

std::string to_string(const KnobValue& value) {
  if (std::holds_alternative<std::monostate>(value)) return "derived per pair";
  if (const bool* b = std::get_if<bool>(&value)) return *b ? "on" : "off";
  if (const double* d = std::get_if<double>(&value)) return number_text(*d);
  return to_string(std::get<Mode>(value));
}

const char* to_string(Mode mode) {
  switch (mode) {
    case Mode::full: return "full";
    case Mode::iterative: return "iterative";
    case Mode::automatic: return "auto";
  }
  return "?";
}

Mode parse_mode(const std::string& text) {
  if (text == "full") return Mode::full;
  if (text == "iterative") return Mode::iterative;
  if (text == "auto") return Mode::automatic;
  throw ConfigError("unknown mode '" + text + "' (expected full, iterative or auto)");
}

void Config::validate() const {
  for (const Knob& k : kKnobs) {
    if (k.type != KnobType::count && k.type != KnobType::length) continue;
    const KnobValue v = k.get(*this);
    const double* d = std::get_if<double>(&v);
    if (d && !(std::isfinite(*d) && *d >= k.min && *d <= k.max))
      throw ConfigError(std::string(k.name) + " = " + number_text(*d) + " is outside [" + number_text(k.min) + ", " +
                        number_text(k.max) + "]");
  }
  if (displacement_threshold && distance_extension && *displacement_threshold > *distance_extension)
    throw ConfigError("displacement_threshold (" + number_text(*displacement_threshold) +
                      ") must not exceed distance_extension (" + number_text(*distance_extension) +
                      "): predictive rays only cover motions up to distance_extension");
}

}  // namespace rtcd
