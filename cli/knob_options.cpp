#include "knob_options.hpp"

namespace rtcd::cli {

void add_knobs(CLI::App& command, app::Knobs& k) {
  for (const Knob& knob : knobs()) {
    const std::string option = app::option_name(knob);
    const std::string cost = std::string(". Cost: ") + knob.cost;
    switch (knob.type) {
      case KnobType::flag:
        // The help says what --no-NAME does, then what the default does.
        command.add_flag_callback("--no-" + option, [&k, &knob] { k.set.push_back({&knob, false}); },
                                  std::string(knob.off) + " (default: on: " + knob.meaning + cost + ")");
        break;
      case KnobType::count:
      case KnobType::length:
        // The range is Config::validate's to hold, with the knob's name.
        command.add_option_function<double>(
            "--" + option, [&k, &knob](double v) { k.set.push_back({&knob, v}); },
            std::string(knob.meaning) + cost + " " + to_string(KnobValue(knob.min)) + " .. " +
                to_string(KnobValue(knob.max)) + " (default: " + knob.unset + ")");
        break;
      case KnobType::mode:
        break;  // each command's own --mode
    }
  }
}

}  // namespace rtcd::cli
