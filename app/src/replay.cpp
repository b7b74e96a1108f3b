// `rtcd replay`: a recording through one configuration, summed per phase.
#include "rtcd/app/replay.hpp"

#include <algorithm>
#include <cstdio>
#include <string>

#include "device_share.hpp"
#include "rtcd/app/console.hpp"
#include "rtcd/error.hpp"
#include "rtcd/experiments/bench.hpp"
#include "rtcd/experiments/replay.hpp"
#include "rtcd/narrow_phase.hpp"

namespace rtcd::app {
namespace {

// One phase's steps summed.
struct Sum {
  std::string name;
  uint64_t steps = 0, peak_step = 0;
  double detect = 0, prepare = 0, full = 0, walks = 0, gather = 0, peak = 0;
  size_t bodies = 0, pairs = 0, pairs_full = 0, fallbacks = 0, contacts = 0, predictive = 0, judged = 0, deep = 0, missed = 0, false_rays = 0;
  size_t missed_pairs = 0, truth_checked = 0, over_reports = 0;
  size_t certified = 0, granted = 0, expired = 0;
  RayCounts counts;
  DeviceWork devices;  // device backends: over the devices and steps

  void add(uint64_t step, const experiments::ReplayStep& s, size_t step_bodies) {
    ++steps;
    bodies += step_bodies;
    detect += s.seconds;
    prepare += s.seconds_prepare;
    full += s.seconds_full;
    walks += s.seconds_iterative;
    gather += s.seconds_gather;
    if (s.seconds > peak) {
      peak = s.seconds;
      peak_step = step;
    }
    pairs += s.pairs;
    pairs_full += s.pairs_full;
    fallbacks += s.fallbacks;
    certified += s.pairs_certified;
    granted += s.certificates_granted;
    expired += s.certificates_expired;
    counts += s.counts;
    for (const DeviceWork& d : s.devices) devices += d;
    contacts += s.contacts;
    predictive += s.predictive;
    judged += s.judged;
    deep += s.deep;
    missed += s.missed;
    false_rays += s.false_rays;
    missed_pairs += s.missed_pairs;
    truth_checked += s.truth_checked;
    over_reports += s.over_reports;
  }
};

// A peer (GIMPACT, FCL) has no stages, modes or rays: those cells say "–".
void print_row(const Sum& s, bool ours) {
  const double n = double(std::max<uint64_t>(s.steps, 1));
  const auto ms = [&](double seconds) { return 1e3 * seconds / n; };
  const auto percent = [&](size_t count) { return s.pairs ? 100.0 * double(count) / double(s.pairs) : 0.0; };
  std::printf("| %s | %llu | %.3f | %.2f (%llu) | ", s.name.c_str(), static_cast<unsigned long long>(s.steps),
              ms(s.detect), 1e3 * s.peak, static_cast<unsigned long long>(s.peak_step));
  if (ours) {
    std::printf("%.3f | %.3f | %.3f | %.3f | %.0f | %.1f%% | %.1f%% | %.0f | %.0f | ", ms(s.prepare), ms(s.full),
                ms(s.walks), ms(s.gather), double(s.pairs) / n, percent(s.pairs_full), percent(s.fallbacks),
                double(s.counts.rays()) / n, double(s.contacts) / n);
  } else {
    std::printf("– | – | – | – | %.0f | – | – | – | %.0f | ", double(s.pairs) / n, double(s.contacts) / n);
  }
  if (s.judged == 0) {
    std::printf("– |\n");
  } else {
    std::printf("%zu: %zu of %zu deep rays missed, %zu false; %zu pairs missed; %zu of %zu contacts over the truth |\n",
                s.judged, s.missed, s.deep, s.false_rays, s.missed_pairs, s.over_reports, s.truth_checked);
  }
}

// Where the rays ran, for a device backend: each device's share, and the
// first step that fell back to the CPU, with why.
void print_devices(const experiments::ReplayRun& run) {
  DeviceShare share;
  for (uint64_t k = 0; k < run.steps.size(); ++k) share.add(k, run.steps[k].devices, run.steps[k].cpu_fallback);
  if (share.rays.empty() && !share.fallback_step) return;  // a CPU backend
  std::printf("\nRays by device:");
  for (size_t d = 0; d < share.rays.size(); ++d) std::printf(" [%zu] %zu", d, share.rays[d]);
  if (share.fallback_step) {
    std::printf("; fell back to the CPU from step %llu: %s\n", static_cast<unsigned long long>(*share.fallback_step),
                share.fallback_reason.c_str());
  } else {
    std::printf("; no step fell back to the CPU\n");
  }
}

// What driving the devices took, per step and phase: commands, blocking
// waits, bytes each way, and the device's own time from profiling events
// (kernels: the thesis' ray time; copies apart). Device backends only.
void print_device_traffic(const std::vector<Sum>& sums) {
  if (sums.empty() || sums.back().devices.launches == 0) return;
  std::printf("\n| devices (per step, over all) |");
  for (const Sum& s : sums) std::printf(" %s |", s.name.c_str());
  std::printf("\n| :-- |");
  for (size_t i = 0; i < sums.size(); ++i) std::printf(" --: |");
  std::printf("\n");
  const auto row = [&](const char* name, auto value, const char* format) {
    std::printf("| %s |", name);
    for (const Sum& s : sums) std::printf(format, value(s) / double(std::max<uint64_t>(s.steps, 1)));
    std::printf("\n");
  };
  const auto work = [](auto field, double scale) { return [=](const Sum& s) { return scale * double(s.devices.*field); }; };
  row("kernel launches", work(&DeviceWork::launches, 1), " %.1f |");
  row("writes", work(&DeviceWork::writes, 1), " %.1f |");
  row("reads", work(&DeviceWork::reads, 1), " %.1f |");
  row("blocking waits", work(&DeviceWork::waits, 1), " %.1f |");
  // The most a device step should move: 64 bytes a body and
  // 16 a pair up; 64 a report and 16 a pair down, recovery apart.
  row("KB to the devices", work(&DeviceWork::bytes_to_device, 1e-3), " %.1f |");
  row("KB to the devices, floor (64 × bodies + 16 × pairs)",
      [](const Sum& s) { return 1e-3 * double(64 * s.bodies + 16 * s.pairs); }, " %.1f |");
  row("KB from the devices", work(&DeviceWork::bytes_from_device, 1e-3), " %.1f |");
  row("KB from the devices, floor (64 × reports + 16 × pairs)",
      [](const Sum& s) { return 1e-3 * double(64 * (s.contacts + s.predictive) + 16 * s.pairs); }, " %.1f |");
  row("KB recovery reads", work(&DeviceWork::bytes_recovery, 1e-3), " %.1f |");
  // What a step must bring back at least: its records.
  row("reports (contacts + predictive rays)", [](const Sum& s) { return double(s.contacts + s.predictive); }, " %.0f |");
  row("kernels (device ms)", work(&DeviceWork::seconds_kernels, 1e3), " %.3f |");
  row("copies (device ms)", work(&DeviceWork::seconds_copies, 1e3), " %.3f |");
}

}  // namespace

int run_replay(const ReplayOptions& o) {
  const sim::Recording recording = sim::Recording::read(o.recording);
  if (recording.steps().empty()) throw UsageError(o.recording + ": holds no steps");
  if (o.last > recording.steps().size())
    throw UsageError("--last " + std::to_string(o.last) + ": " + o.recording + " holds only " +
                     std::to_string(recording.steps().size()) + " steps");
  experiments::ReplayConfig c;
  if (!o.peer.empty()) {
    if (o.peer != "gimpact" && o.peer != "fcl") throw UsageError("--peer " + o.peer + ": gimpact or fcl");
    if (o.judge_every > 0 || !o.knobs.set.empty())
      throw UsageError("--peer " + o.peer + ": --judge-every and the knobs are rtcd's");
    c.engine = o.peer == "gimpact" ? experiments::Engine::gimpact : experiments::Engine::fcl;
  }
  const bool ours = c.engine == experiments::Engine::ours;
  c.label = ours ? o.backend + " " + o.mode : experiments::to_string(c.engine);
  c.backend = o.backend;
  c.config = recording.scene().narrow;
  c.config.mode = parse_mode(o.mode);
  o.knobs.apply(c.config);
  c.threads = o.threads;
  experiments::ReplayOptions ro;
  ro.judge_every = o.judge_every;
  Progress bar(recording.steps().size(), "replay");
  ro.progress = [&](uint64_t done, uint64_t) { bar.update(done); };
  const experiments::ReplayRun run = experiments::replay(recording, {c}, ro).front();

  const experiments::Phases phases = experiments::find_phases(recording.steps());
  if (ours) {
    std::printf("%s: scene %s, %zu steps; %s, mode %s, %d thread%s; machine %s\n", o.recording.c_str(),
                recording.scene().name.c_str(), recording.steps().size(), run.engine_name.c_str(), o.mode.c_str(),
                o.threads, o.threads == 1 ? "" : "s", machine().c_str());
  } else {
    std::printf("%s: scene %s, %zu steps; %s (%s), one thread; machine %s\n", o.recording.c_str(),
                recording.scene().name.c_str(), recording.steps().size(), c.label.c_str(), run.engine_name.c_str(),
                machine().c_str());
  }
  std::printf("Phases: %s\n\n", phases.rule().c_str());
  std::printf(
      "| phase | steps | detect (ms) | peak (ms, step) | prepare | full tracing | walks | gather | pairs | traced in "
      "full | sent back | rays | contacts | judged steps |\n");
  std::printf("| :-- | --: | --: | --: | --: | --: | --: | --: | --: | --: | --: | --: | --: | :-- |\n");
  std::vector<Sum> sums;  // the phases with steps, then all
  for (const char phase : {'-', 'A', 'B', 'C'}) {
    Sum sum;
    sum.name = phase == '-' ? "before A" : std::string(1, phase);
    for (uint64_t k = 0; k < run.steps.size(); ++k)
      if (phases.of(k) == phase) sum.add(k, run.steps[k], recording.steps()[k].bodies);
    if (sum.steps > 0) sums.push_back(sum);
  }
  if (o.last > 0) {
    Sum& tail = sums.emplace_back();
    tail.name = "last " + std::to_string(o.last);
    for (uint64_t k = run.steps.size() - o.last; k < run.steps.size(); ++k) tail.add(k, run.steps[k], recording.steps()[k].bodies);
  }
  Sum& all = sums.emplace_back();
  all.name = "all";
  for (uint64_t k = 0; k < run.steps.size(); ++k) all.add(k, run.steps[k], recording.steps()[k].bodies);
  for (const Sum& s : sums) print_row(s, ours);
  if (!ours) {
    std::printf("\nMeans per step; detect: every pair's collide, one thread; contacts as the library reports them (a peer has no stages or rays).\n");
    return 0;
  }
  print_devices(run);
  print_device_traffic(sums);
  // Where the rays went: each counter of kRayCounters, per step, per phase.
  std::printf("\n| counter (per step) |");
  for (const Sum& s : sums) std::printf(" %s |", s.name.c_str());
  std::printf("\n| :-- |");
  for (size_t i = 0; i < sums.size(); ++i) std::printf(" --: |");
  std::printf("\n");
  for (const RayCounter& c : kRayCounters) {
    std::printf("| %s |", c.name);
    for (const Sum& s : sums) std::printf(" %.0f |", double(s.counts.*c.field) / double(std::max<uint64_t>(s.steps, 1)));
    std::printf("\n");
  }
  // The pairs that cast nothing (StepStats, Config::trace_separated_pairs off).
  for (const auto& [name, field] : {std::pair{"pairs_certified", &Sum::certified},
                                    std::pair{"certificates_granted", &Sum::granted},
                                    std::pair{"certificates_expired", &Sum::expired}}) {
    std::printf("| %s |", name);
    for (const Sum& s : sums) std::printf(" %.1f |", double(s.*field) / double(std::max<uint64_t>(s.steps, 1)));
    std::printf("\n");
  }
  std::printf("\nMeans per step; prepare, full tracing, walks and gather are the stages of detect (StepStats); sent back: pairs traced in full because equation 2.1 ended their walks (the others traced in full are new); rays: vertex rays traced in full, predictive and walked (RayCounts::rays; edge rays are counted apart).\n");
  return 0;
}

}  // namespace rtcd::app
