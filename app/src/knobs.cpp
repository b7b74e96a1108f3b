#include "rtcd/app/knobs.hpp"

#include "rtcd/app/inputs.hpp"
#include "rtcd/config.hpp"
#include "rtcd/results.hpp"

namespace rtcd::app {
namespace {

std::string range(const Knob& k) {
  switch (k.type) {
    case KnobType::flag:
      return "on, off";
    case KnobType::mode:
      return "full, iterative, auto";
    default: {
      // Appended, not "[" + ...: GCC 12 warns falsely (-Wrestrict) on that.
      std::string text(1, '[');
      text += to_string(KnobValue(k.min));
      text += ", ";
      text += to_string(KnobValue(k.max));
      return text += ']';
    }
  }
}

const char* type_name(KnobType t) {
  switch (t) {
    case KnobType::flag: return "switch";
    case KnobType::count: return "count";
    case KnobType::length: return "length";
    case KnobType::mode: return "mode";
  }
  return "?";
}

std::string option(const Knob& k) {
  const std::string name = option_name(k);
  if (k.type == KnobType::mode) return "each command's `--mode`";
  return k.type == KnobType::flag ? "`--no-" + name + "`" : "`--" + name + "`";
}

}  // namespace

void print_knobs(std::ostream& out) {
  out << "## Knobs\n\n"
         "| knob | type | range | default | meaning | cost | command line | scene |\n"
         "|---|---|---|---|---|---|---|---|\n";
  for (const Knob& k : knobs())
    out << "| `" << k.name << "` | " << type_name(k.type) << " | " << range(k) << " | " << k.unset << " | " << k.meaning
        << " | " << k.cost << " | " << option(k) << " | "
        << (k.effect ? "`\"" + std::string(k.name) + "\"` in `effects`" : "`narrow_phase." + std::string(k.name) + "`")
        << " |\n";
  out << "\n## Step statistics\n\n"
         "Counters of `StepStats` (`rtcd query --json`, `stats`), summed over a step's pairs.\n\n"
         "| counter | what it counts |\n"
         "|---|---|\n";
  for (const StepCounter& c : kStepCounters) out << "| `" << c.name << "` | " << c.meaning << " |\n";
  for (const RayCounter& c : kRayCounters) out << "| `" << c.name << "` | " << c.meaning << " |\n";
}

}  // namespace rtcd::app
