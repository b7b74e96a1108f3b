// `rtcd bench`: record, replay, simulate the variants, write the tables.
#include "rtcd/experiments/bench.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <numeric>
#include <sstream>
#include <thread>

#include <tbb/task_arena.h>

#include "rtcd/backend.hpp"
#include "rtcd/clock.hpp"
#include "rtcd/experiments/replay.hpp"
#include "rtcd/narrow_phase.hpp"
#include "rtcd/sim/simulation.hpp"

namespace rtcd::experiments {
namespace {

std::string limit_text(const std::optional<double>& value) {
  if (!value) return "derived per pair";
  std::ostringstream s;
  s << *value;
  return s.str();
}

namespace fs = std::filesystem;

std::string fixed(double v, int digits) {
  if (!std::isfinite(v)) return "–";
  std::ostringstream s;
  s << std::fixed << std::setprecision(digits) << v;
  return s.str();
}
std::string ms(double seconds) { return fixed(1e3 * seconds, seconds < 0.001 ? 3 : 2); }
std::string ratio(double v) { return std::isfinite(v) ? fixed(v, v < 10 ? 2 : 1) + "×" : "–"; }
std::string percent(double v) { return std::isfinite(v) ? fixed(100 * v, v < 0.01 ? 3 : 2) + "%" : "–"; }

// A table written as Markdown into the report and as CSV beside it.
struct Table {
  std::vector<std::string> header;
  std::vector<std::vector<std::string>> rows;

  void markdown(std::ostream& out) const {
    const auto line = [&](const std::vector<std::string>& cells) {
      out << '|';
      for (const auto& c : cells) out << ' ' << c << " |";
      out << '\n';
    };
    line(header);
    out << '|';
    for (size_t i = 0; i < header.size(); ++i) out << (i == 0 ? " :-- |" : " --: |");
    out << '\n';
    for (const auto& r : rows) line(r);
    out << '\n';
  }
  void csv(const fs::path& path) const {
    std::ofstream out(path);
    if (!out) throw UsageError("cannot write " + path.string());
    const auto line = [&](const std::vector<std::string>& cells) {
      for (size_t i = 0; i < cells.size(); ++i) {
        std::string c = cells[i];
        std::erase(c, '*');
        if (c.ends_with("×")) c.resize(c.size() - std::string("×").size());
        out << (i ? "," : "") << (c.find(',') != std::string::npos ? '"' + c + '"' : c);
      }
      out << '\n';
    };
    line(header);
    for (const auto& r : rows) line(r);
  }
};

// Statistics of one replay run over a range of steps, on the steps it ran.
struct Stats {
  size_t n = 0;
  double mean = NAN, peak = NAN, median = NAN;
};
template <class F>
Stats stats(const ReplayRun& run, uint64_t begin, uint64_t end, F value, const std::vector<bool>* only = nullptr) {
  std::vector<double> v;
  for (uint64_t s = begin; s < std::min<uint64_t>(end, run.steps.size()); ++s)
    if (run.steps[s].ran && (!only || (*only)[s])) v.push_back(value(run.steps[s]));
  Stats out;
  out.n = v.size();
  if (v.empty()) return out;
  out.mean = std::accumulate(v.begin(), v.end(), 0.0) / double(v.size());
  out.peak = *std::max_element(v.begin(), v.end());
  std::nth_element(v.begin(), v.begin() + std::ptrdiff_t(v.size() / 2), v.end());
  out.median = v[v.size() / 2];
  return out;
}
double rays_of(const ReplayStep& s) { return s.seconds_rays(); }
double whole_of(const ReplayStep& s) { return s.seconds; }

struct Judged {
  size_t deep = 0, missed = 0, false_rays = 0;
  double rate() const { return deep ? double(missed) / double(deep) : NAN; }
};
Judged judged(const ReplayRun& run) {
  Judged j;
  for (const ReplayStep& s : run.steps)
    if (s.judged) {
      j.deep += s.deep;
      j.missed += s.missed;
      j.false_rays += s.false_rays;
    }
  return j;
}

// The scene with only these of the contact effects, the knobs set to match.
sim::Scene with_effects(sim::Scene scene, bool predictive, bool speculative, bool projected) {
  for (auto [effect, on] : {std::pair{sim::Effect::predictive, predictive}, {sim::Effect::speculative, speculative},
                            {sim::Effect::projected, projected}}) {
    if (on) scene.effects.insert(effect);
    else scene.effects.erase(effect);
  }
  scene.effects.insert(sim::Effect::interpenetration);
  scene.effects.erase(sim::Effect::snapshots);
  scene.narrow.predictive = predictive;
  scene.narrow.projected = projected;
  // Tables 2.3 and 2.4 are the thesis' ray contacts, whose push projection
  // changes; the defaults' nearest-surface contacts are a variant of their own.
  scene.narrow.nearest_surface = false;
  return scene;
}

// A simulation to its end; what the interpenetration pass measured last.
struct SimOutcome {
  double interpenetration = NAN, projected = NAN, deepest = NAN, seconds = 0, narrow_seconds = 0;
  double true_penetration = NAN, deepest_true = NAN;  // the same pass, measured to the nearest surface
  std::string error;
};
SimOutcome simulate(const sim::Scene& scene, const std::string& backend,
                    const std::function<void(uint64_t, uint64_t)>& progress) {
  SimOutcome o;
  const auto t = Clock::now();
  try {
    sim::Simulation simulation(scene, backend);
    for (uint64_t i = 0; i < scene.steps; ++i) {
      o.narrow_seconds += simulation.step().seconds_narrow;
      if (progress) progress(i + 1, scene.steps);
    }
    o.interpenetration = simulation.last().interpenetration;
    o.projected = simulation.last().projected;
    o.deepest = simulation.last().deepest;
    o.true_penetration = simulation.last().true_penetration;
    o.deepest_true = simulation.last().deepest_true;
  } catch (const sim::SimulationError& e) {
    o.error = e.what();
  }
  o.seconds = seconds_since(t);
  return o;
}

// A path as the reader would type it from here: relative when inside the
// current folder.
std::string shown(const std::string& path) {
  const fs::path relative = fs::path(path).lexically_relative(fs::current_path());
  return relative.empty() || *relative.begin() == ".." ? path : relative.string();
}

double mean_of(const std::vector<double>& v) {
  return v.empty() ? NAN : std::accumulate(v.begin(), v.end(), 0.0) / double(v.size());
}

// A figure over seeds: the mean, and min – max.
std::string spread(const std::vector<double>& v) {
  if (v.empty()) return std::string("blew up");
  const auto [lo, hi] = std::minmax_element(v.begin(), v.end());
  return fixed(mean_of(v), 4) + " (" + fixed(*lo, 4) + " – " + fixed(*hi, 4) + ")";
}

std::string decrease(const std::vector<double>& without, const std::vector<double>& with) {
  return percent(1 - mean_of(with) / mean_of(without));
}

// The automatic mode's threshold scaled for the accuracy/time curve, where
// it stays within the distance extension.
std::vector<double> swept_thresholds(const Config& base) {
  std::vector<double> thresholds;
  if (base.displacement_threshold)  // a derived threshold differs per pair: nothing to scale
    for (double t : {0.25, 0.5, 2.0})
      if (t * *base.displacement_threshold <= base.distance_extension.value_or(HUGE_VAL))
        thresholds.push_back(t * *base.displacement_threshold);
  return thresholds;
}

}  // namespace

std::string Phases::rule() const {
  std::ostringstream s;
  s << "A (free fall) from the first step with broad-phase pairs to the first ground contact: steps [" << a_begin << ", "
    << b_begin << "); B (impact) until the kinetic energy, past its peak, falls below " << settle_fraction * 100
    << "% of the peak: [" << b_begin << ", " << c_begin << "); C (settled) the rest: [" << c_begin << ", " << end << ")";
  return s.str();
}

char Phases::of(uint64_t step) const {
  if (step < a_begin) return '-';
  if (step < b_begin) return 'A';
  if (step < c_begin) return 'B';
  return 'C';
}

Phases find_phases(const std::vector<sim::RecordedStep>& steps, double settle_fraction) {
  Phases p;
  p.settle_fraction = settle_fraction;
  p.end = steps.size();
  const auto first = [&](uint64_t from, auto predicate) {
    for (uint64_t s = from; s < steps.size(); ++s)
      if (predicate(steps[s])) return s;
    return uint64_t(steps.size());
  };
  p.a_begin = first(0, [](const sim::RecordedStep& s) { return s.pairs > 0; });
  p.b_begin = std::max(p.a_begin, first(0, [](const sim::RecordedStep& s) { return s.ground_contacts > 0; }));
  uint64_t peak = p.b_begin;
  for (uint64_t s = p.b_begin; s < steps.size(); ++s)
    if (steps[s].kinetic_energy > steps[peak].kinetic_energy) peak = s;
  p.c_begin = p.b_begin >= steps.size()
                  ? p.end
                  : first(peak, [&](const sim::RecordedStep& s) {
                      return s.kinetic_energy < settle_fraction * steps[peak].kinetic_energy;
                    });
  return p;
}

Motion largest_motion(const sim::Recording& recording) {
  Motion m;
  m.distance_extension = recording.scene().narrow.distance_extension;
  const auto shapes = sim::make_shapes(recording.scene());
  std::vector<double> radius;
  for (uint32_t k : recording.kinds())
    radius.push_back(k == sim::Simulation::kGroundKind ? 0.0 : shapes[k]->radius());
  sim::Recording::Cursor cursor(recording);
  sim::RecordedFrame frame, before;
  while (cursor.next(frame)) {
    for (size_t b = 0; b < before.poses.size(); ++b) {
      const Pose& p0 = before.poses[b];
      const Pose& p1 = frame.poses[b];
      const double moved = (p1.position - p0.position).norm() + p0.orientation.angularDistance(p1.orientation) * radius[b];
      if (moved > m.largest) {
        m.largest = moved;
        m.step = cursor.index();
        m.body = uint32_t(b);
      }
    }
    std::swap(before, frame);
  }
  m.speed = m.largest / recording.scene().time_step;
  return m;
}

namespace {

// Contact points per pair in the thesis' Table 2.4: Bullet's usual manifold.
constexpr uint32_t kThesisPointsPerPair = 4;

// The defaults' contacts, measured to the nearest surface, beside Table 2.4's.
constexpr const char* kNearestVariant = "projected constraints, nearest-surface contacts (the defaults)";

// A simulated variant of the scene, for Tables 2.3 and 2.4 and the accuracy curve.
struct Variant {
  std::string table, label;
  sim::Scene scene;
  std::string backend;
  bool seeded;
};
struct Outcome {
  const Variant* variant;
  uint64_t seed;
  SimOutcome result;
};

// One `rtcd bench`: its stages fill what the report's tables and figures
// read, one method each.
class Bench {
 public:
  explicit Bench(const BenchOptions& o) : o(o), dir(o.out) {}

  std::string run() {
    std::error_code ec;
    fs::create_directories(dir, ec);
    if (ec) throw UsageError("cannot create the output folder " + dir.string() + ": " + ec.message());
    record();
    replay_configurations();
    host_gimpact();
    simulate_variants();
    std::ofstream report(dir / "report.md");
    if (!report) throw UsageError("cannot write " + (dir / "report.md").string());
    introduction(report);
    table_2_1(report);
    if (cores > 1) peak_step(report);
    figure_2_12(report);
    figures_2_13_and_2_14(report);
    peers(report);
    interpenetration_tables(report);
    accuracy_curve(report);
    return (dir / "report.md").string();
  }

 private:
  // 1. The recording (or the one given): one thread, as Bullet's GIMPACT host runs.
  void record();
  // 2. The replays, in lockstep.
  void replay_configurations();
  ReplayConfig our_config(std::string label, std::string backend, Mode mode, int threads, double threshold = -1) const;
  // 3. The same scene with Bullet's GIMPACT as the narrow phase (Figure 2.12).
  void host_gimpact();
  // 4. Simulations for the interpenetration tables and the accuracy curve.
  void simulate_variants();
  // 5. The report.
  void introduction(std::ostream& report) const;
  void table_2_1(std::ostream& report) const;
  void peak_step(std::ostream& report) const;  // on every core: where the time goes
  void figure_2_12(std::ostream& report) const;
  void figures_2_13_and_2_14(std::ostream& report) const;
  void write_replay_steps() const;
  void write_host_steps() const;
  void peers(std::ostream& report) const;  // on the sampled steps
  void interpenetration_tables(std::ostream& report) const;  // Tables 2.3 and 2.4, and the same runs' other figures
  void write_simulations() const;
  void table_2_3(std::ostream& report) const;
  void table_2_4(std::ostream& report) const;
  void projected_interpenetration(std::ostream& report) const;
  void true_penetration(std::ostream& report) const;
  void accuracy_curve(std::ostream& report) const;
  // A variant's figure over its seeds that did not blow up: the summed ray
  // depth (the thesis'), or another the interpenetration pass measured.
  std::vector<double> over_seeds(const std::string& label,
                                 double SimOutcome::*figure = &SimOutcome::interpenetration) const;

  std::function<void(uint64_t, uint64_t)> progress(const std::string& stage) const {
    return [this, stage](uint64_t done, uint64_t total) {
      if (o.progress) o.progress(stage, done, total);
    };
  }
  const ReplayRun& run_of(const std::string& label) const {
    for (const ReplayRun& r : runs)
      if (r.config.label == label) return r;
    throw std::logic_error("no run " + label);
  }

  const BenchOptions& o;
  const fs::path dir;
  const int cores = int(std::max(1u, std::thread::hardware_concurrency()));
  const std::string n_threads = std::to_string(cores) + " threads";
  sim::Recording recording;
  sim::Scene scene;  // the recording's, simulating as many steps as were recorded
  uint64_t steps = 0;
  Phases phases;
  Motion motion;
  uint64_t full_every = 1, peers_every = 1, judge_every = 1, host_steps = 1;
  Config base;
  std::vector<std::string> tracers;  // usable backends
  std::vector<ReplayConfig> configs;
  std::vector<ReplayRun> runs;
  std::vector<sim::StepRecord> gimpact_host;
  bool speculative = false;
  std::vector<Variant> variants;
  std::vector<Outcome> outcomes;
};

void Bench::record() {
  std::string recording_path = o.replay;
  if (recording_path.empty()) {
    std::ifstream in(o.scene);
    if (!in) throw UsageError(o.scene + ": cannot open");
    std::ostringstream text;
    text << in.rdbuf();
    // The recorded run is also the host comparison's: no passes beside the step.
    sim::Scene recorded = sim::parse_scene(text.str(), o.scene);
    if (o.steps) recorded.steps = o.steps;
    recorded.effects.erase(sim::Effect::interpenetration);
    recorded.effects.erase(sim::Effect::snapshots);
    recording_path = (dir / "recording.rtcdrec").string();
    sim::RecordingWriter writer(recording_path, o.scene, text.str());
    tbb::task_arena one(1);
    one.execute([&] {
      sim::Simulation simulation(recorded);
      for (uint64_t i = 0; i < recorded.steps; ++i) {
        simulation.step();
        writer.append(simulation);
        progress("record (1 thread)")(i + 1, recorded.steps);
      }
    });
    writer.close();
  }
  recording = sim::Recording::read(recording_path);
  // The variants below simulate as many steps as were recorded.
  scene = recording.scene();
  scene.steps = recording.steps().size();
  steps = recording.steps().size();
  if (steps == 0) throw UsageError(recording_path + ": holds no steps");
  phases = find_phases(recording.steps());
  motion = largest_motion(recording);
}

void Bench::replay_configurations() {
  full_every = o.full_every ? o.full_every : std::max<uint64_t>(1, steps / 60);
  peers_every = o.peers_every ? o.peers_every : std::max<uint64_t>(1, steps / 60);
  judge_every = o.judge_every ? o.judge_every : std::max<uint64_t>(1, steps / 20);
  base = scene.narrow;
  // Full and automatic on every usable backend; the knobs on Embree, the reference.
  for (const BackendInfo& b : available_backends())
    if (b.usable) tracers.push_back(b.name);
  for (const std::string& t : tracers) {
    configs.push_back(our_config("full " + t, t, Mode::full, 1));
    configs.push_back(our_config("auto " + t, t, Mode::automatic, 1));
  }
  configs.push_back(our_config("iterative embree", "embree", Mode::iterative, 1));
  // The accuracy/time curve: the automatic mode's threshold swept.
  for (double t : swept_thresholds(base))
    configs.push_back(our_config("auto embree, threshold " + fixed(t, 3), "embree", Mode::automatic, 1, t));
  if (cores > 1) {
    configs.push_back(our_config("full embree, " + n_threads, "embree", Mode::full, cores));
    configs.push_back(our_config("auto embree, " + n_threads, "embree", Mode::automatic, cores));
  }
  for (Engine e : {Engine::gimpact, Engine::fcl}) {
    ReplayConfig c;
    c.label = to_string(e);
    c.engine = e;
    c.every = peers_every;
    c.budget_seconds = o.budget_seconds;
    configs.push_back(c);
  }
  ReplayOptions ro;
  ro.judge_every = judge_every;
  ro.progress = progress("replay");
  runs = replay(recording, configs, ro);
}

ReplayConfig Bench::our_config(std::string label, std::string backend, Mode mode, int threads, double threshold) const {
  ReplayConfig c;
  c.label = std::move(label);
  c.backend = std::move(backend);
  c.config = base;
  c.config.mode = mode;
  if (threshold >= 0) c.config.displacement_threshold = threshold;
  c.threads = threads;
  // Brute force in full mode is sampled: it costs rays x triangles a step.
  const bool brute_force = c.backend == "basic" || c.backend == "opencl-basic";
  c.every = mode == Mode::full && brute_force ? full_every : 1;
  c.budget_seconds = o.budget_seconds;
  return c;
}

void Bench::host_gimpact() {
  host_steps = std::min(steps, std::max<uint64_t>(1, o.gimpact_host_steps));
  sim::Scene s = scene;
  s.steps = host_steps;
  s.effects.erase(sim::Effect::interpenetration);
  s.effects.erase(sim::Effect::snapshots);
  sim::Simulation simulation(s, sim::kGimpact);
  for (uint64_t i = 0; i < host_steps; ++i) {
    gimpact_host.push_back(simulation.step());
    progress("GIMPACT host")(i + 1, host_steps);
  }
}

void Bench::simulate_variants() {
  speculative = scene.has(sim::Effect::speculative);
  variants.push_back({"2.3", "no predictive rays", with_effects(scene, false, false, true), "", true});
  variants.push_back({"2.3", "predictive rays", with_effects(scene, true, false, true), "", true});
  variants.push_back({"2.3", "predictive rays + speculative contacts", with_effects(scene, true, true, true), "", true});
  variants.push_back({"2.4", "standard constraints", with_effects(scene, true, speculative, false), "", true});
  variants.push_back({"2.4", "projected constraints", with_effects(scene, true, speculative, true), "", true});
  sim::Scene nearest = with_effects(scene, true, speculative, true);
  nearest.narrow.nearest_surface = true;
  variants.push_back({"2.4", kNearestVariant, std::move(nearest), "", true});
  // Table 2.4 as the thesis measured it: no speculative contacts, and
  // Bullet's usual four contact points per pair.
  for (const bool projected : {false, true}) {
    sim::Scene s = with_effects(scene, true, false, projected);
    s.points_per_pair = kThesisPointsPerPair;
    variants.push_back({"2.4", std::string(projected ? "projected" : "standard") + " constraints, as the thesis ran",
                        std::move(s), "", true});
  }
  for (const ReplayConfig& c : configs) {
    // Simulated with Embree only: the tracers find the same contacts.
    if (c.engine != Engine::ours || c.threads != 1 || c.backend != "embree") continue;
    sim::Scene s = with_effects(scene, base.predictive, speculative, base.projected);
    s.narrow = c.config;
    variants.push_back({"accuracy", c.label, s, c.backend, false});
  }
  size_t total_runs = 0, done_runs = 0;
  for (const Variant& v : variants) total_runs += v.seeded ? o.seeds : 1;
  for (const Variant& v : variants) {
    for (uint32_t k = 0; k < (v.seeded ? o.seeds : 1u); ++k) {
      sim::Scene s = v.scene;
      s.seed = scene.seed + k;
      ++done_runs;
      const std::string stage = "simulation " + std::to_string(done_runs) + "/" + std::to_string(total_runs);
      outcomes.push_back({&v, s.seed, simulate(s, v.backend, progress(stage))});
    }
  }
}

void Bench::introduction(std::ostream& report) const {
  size_t triangles_at_end = 0;
  {
    const auto shapes = sim::make_shapes(scene);
    for (uint32_t k : recording.kinds())
      if (k != sim::Simulation::kGroundKind) triangles_at_end += shapes[k]->mesh() ? shapes[k]->mesh()->triangle_count() : 0;
  }
  size_t peak_pairs = 0;
  for (const auto& s : recording.steps()) peak_pairs = std::max<size_t>(peak_pairs, s.pairs);
  report << "# `rtcd bench " << scene.name << "`\n\n" << o.command << "\n\n";
  report << "Scene `" << shown(scene.path) << "`: " << recording.steps().back().bodies << " bodies at the end (ground included), "
         << triangles_at_end << " triangles; " << steps << " steps of " << fixed(scene.time_step * 1e3, 2)
         << " ms; up to " << peak_pairs << " broad-phase pairs per step (" << recording.steps().back().pairs
         << " on the last). Distance extension " << limit_text(base.distance_extension) << ", displacement threshold "
         << limit_text(base.displacement_threshold) << ", " << scene.points_per_pair
         << " contact points per pair reach the solver (the deepest ray, then the farthest-point spread; speculative"
            " gaps in what is left, those that close within the step first).\n\n";
  report << "Largest per-step motion of a surface point: " << fixed(motion.largest, 4) << " (" << fixed(motion.speed, 2)
         << " per second, step " << motion.step << ", body " << motion.body << ") against the distance extension "
         << limit_text(motion.distance_extension) << ": "
         << (motion.largest > motion.distance_extension.value_or(0.0)
                 ? "larger, so a predictive ray cannot see every impact one step ahead; those are found by full "
                   "tracing once they penetrate."
                 : "within it, so predictive rays see every impact one step ahead.")
         << "\n\nPhases: " << phases.rule() << ".\n\n";
  report << "Sampling: full tracing with the basic tracers (basic, opencl-basic) replayed every " << full_every << " step(s), GIMPACT and FCL every " << peers_every
         << ", rays judged by the exact reference every " << judge_every
         << "; iterative and automatic configurations run on every step. Replays on one thread unless the label says "
            "otherwise. The recording was simulated on one thread. A configuration stops once its steps have taken "
         << o.budget_seconds << " s in all";
  bool any_stopped = false;
  for (const ReplayRun& r : runs)
    if (r.stopped()) {
      report << (any_stopped ? "; " : ": ") << r.config.label << " stopped at step " << r.stopped_at << " ("
             << recording.steps()[r.stopped_at].bodies << " bodies)";
      any_stopped = true;
    }
  report << (any_stopped ? ".\n\n" : "; none did.\n\n");
}

// Table 2.1.
void Bench::table_2_1(std::ostream& report) const {
  Table t;
  t.header = {"configuration (1 thread)", "mean ray time in A (ms)", "peak in B (ms)", "mean in C (ms)",
              "missed rays (judged steps)", "false rays (judged steps)"};
  Table s;
  s.header = {"speedup, automatic over full", "A (mean)", "B (peak)", "C (mean)"};
  for (const std::string& tracer : tracers) {
    const ReplayRun& full = run_of("full " + tracer);
    const ReplayRun& autom = run_of("auto " + tracer);
    Stats f[3], a[3];
    const uint64_t bounds[4] = {phases.a_begin, phases.b_begin, phases.c_begin, phases.end};
    for (int p = 0; p < 3; ++p) {
      f[p] = stats(full, bounds[p], bounds[p + 1], rays_of);
      a[p] = stats(autom, bounds[p], bounds[p + 1], rays_of);
    }
    for (const auto& [run, st] : {std::pair{&full, f}, std::pair{&autom, a}})
      t.rows.push_back({run->config.label, ms(st[0].mean), ms(st[1].peak), ms(st[2].mean), percent(judged(*run).rate()),
                        std::to_string(judged(*run).false_rays)});
    // Speedups over the steps both ran: a sampled or stopped run's steps
    // differ from the other's, and ray time drifts within a phase.
    std::vector<bool> both(std::max(full.steps.size(), autom.steps.size()));
    for (size_t k = 0; k < both.size(); ++k)
      both[k] = k < full.steps.size() && full.steps[k].ran && k < autom.steps.size() && autom.steps[k].ran;
    double speedups[3];
    for (int p = 0; p < 3; ++p) {
      const Stats fb = stats(full, bounds[p], bounds[p + 1], rays_of, &both);
      const Stats ab = stats(autom, bounds[p], bounds[p + 1], rays_of, &both);
      speedups[p] = p == 1 ? fb.peak / ab.peak : fb.mean / ab.mean;
    }
    s.rows.push_back({tracer, ratio(speedups[0]), ratio(speedups[1]), ratio(speedups[2])});
  }
  report << "## Table 2.1: ray time per phase, full tracing against the automatic mode\n\n"
            "Ray time is tracing and walking (StepStats seconds_full + seconds_iterative), as the thesis timed. "
            "Speedups are taken over the steps both configurations ran. "
            "Missed rays: ray origins the exact reference puts deeper than 1e-5 × the larger radius inside the "
            "other body with no contact, over every judged step.\n\n";
  t.markdown(report);
  s.markdown(report);
  t.csv(dir / "table_2_1.csv");
  s.csv(dir / "table_2_1_speedups.csv");
}

void Bench::peak_step(std::ostream& report) const {
  const ReplayRun& r = run_of("auto embree, " + n_threads);
  uint64_t peak = 0;
  for (uint64_t i = 0; i < r.steps.size(); ++i)
    if (r.steps[i].seconds > r.steps[peak].seconds) peak = i;
  const ReplayStep& p = r.steps[peak];
  const Stats whole = stats(r, 0, steps, whole_of);
  report << "## The peak step, automatic mode on " << n_threads << "\n\n"
         << "Narrow phase (detect) per step: mean " << ms(whole.mean) << " ms, peak " << ms(p.seconds)
         << " ms at step " << peak << " (phase " << phases.of(peak) << ", " << p.pairs << " pairs: " << p.pairs_full
         << " traced in full, " << p.pairs_iterative << " walked; " << p.counts.rays() << " rays). The real-time budget at "
         << fixed(1 / scene.time_step, 0) << " Hz is " << ms(scene.time_step) << " ms: "
         << (p.seconds <= scene.time_step ? "met" : "missed by " + ms(p.seconds - scene.time_step) + " ms")
         << ". Core time per pair at the peak: " << fixed(1e6 * p.seconds * cores / double(std::max<size_t>(1, p.pairs)), 2)
         << " µs.\n\n";
  Table t;
  t.header = {"stage of the peak step", "ms", "share"};
  for (const auto& [name, v] : {std::pair{"prepare (bounds, candidate vertices, pair state)", p.seconds_prepare},
                                {"full tracing", p.seconds_full},
                                {"iterative walks", p.seconds_iterative},
                                {"gather (results in pair order)", p.seconds_gather},
                                {"rest of detect", p.seconds - p.seconds_prepare - p.seconds_full -
                                                       p.seconds_iterative - p.seconds_gather}})
    t.rows.push_back({name, ms(v), percent(v / p.seconds)});
  t.markdown(report);
  t.csv(dir / "peak_step.csv");
}

// Figure 2.12: the whole step in the host.
void Bench::figure_2_12(std::ostream& report) const {
  Table t;
  t.header = {"host, first " + std::to_string(host_steps) + " steps, 1 thread", "broad phase (ms)",
              "narrow phase (ms)", "solver (ms)", "other (ms)", "whole step (ms)"};
  double b = 0, n = 0, s = 0, e = 0, w = 0;
  for (uint64_t i = 0; i < host_steps; ++i) {
    const sim::RecordedStep& r = recording.steps()[i];
    b += r.seconds_broad, n += r.seconds_narrow, s += r.seconds_solver, e += r.seconds_effects, w += r.seconds_total;
  }
  const double k = 1.0 / double(host_steps);
  t.rows.push_back({"rtcd (" + make_narrow_phase(scene.backend, base)->name() + ", " + to_string(base.mode) + " mode)", ms(b * k), ms(n * k), ms(s * k),
                    ms(e * k), ms(w * k)});
  const double ours_whole = w * k;
  b = n = s = e = w = 0;
  for (const sim::StepRecord& r : gimpact_host)
    b += r.seconds_broad, n += r.seconds_narrow, s += r.seconds_solver, e += r.seconds_effects, w += r.seconds_total;
  t.rows.push_back({"Bullet GIMPACT", ms(b * k), ms(n * k), ms(s * k), ms(e * k), ms(w * k)});
  report << "## Figure 2.12: the whole simulation step, rtcd against GIMPACT in the same host\n\n"
            "Both simulations start from the same scene; from the first contact on they follow their own "
            "trajectories (their contacts differ). Whole step "
         << ratio(w * k / ours_whole) << " faster with rtcd.\n\n";
  t.markdown(report);
  t.csv(dir / "figure_2_12.csv");
  report << "![Figure 2.12](figure_2_12.png)\n\n";
}

// Figure 2.13 / 2.14 data.
void Bench::figures_2_13_and_2_14(std::ostream& report) const {
  write_replay_steps();
  write_host_steps();
  report << "## Figure 2.13: ray time per step, every configuration\n\n![Figure 2.13](figure_2_13.png)\n\n";
  // The end of the run (its last tenth): the speedups of Figure 2.14.
  // The last tenth of the steps both configurations of a tracer ran.
  Table t;
  t.header = {"end of the run, 1 thread", "steps", "bodies", "full: mean ray time (ms)", "automatic (ms)", "speedup"};
  for (const std::string& tracer : tracers) {
    const ReplayRun& full = run_of("full " + tracer);
    const ReplayRun& autom = run_of("auto " + tracer);
    const uint64_t end = std::min({steps, full.stopped_at, autom.stopped_at});
    if (end == 0) continue;
    const uint64_t begin = end - std::min(end, std::max<uint64_t>(1, steps / 10));  // a run stopped early: from 0
    const double f = stats(full, begin, end, rays_of).mean;
    const double a = stats(autom, begin, end, rays_of).mean;
    t.rows.push_back({tracer, "[" + std::to_string(begin) + ", " + std::to_string(end) + ")",
                      std::to_string(recording.steps()[begin].bodies) + " – " +
                          std::to_string(recording.steps()[end - 1].bodies),
                      ms(f), ms(a), ratio(f / a)});
  }
  report << "## Figure 2.14: ray time against the body count\n\n";
  if (recording.steps().front().bodies == recording.steps().back().bodies)
    report << "The body count does not change in this scene (Figure 2.13 shows its ray time per step); the "
              "speedups at its end:\n\n";
  else
    report << "![Figure 2.14](figure_2_14.png)\n\n";
  t.markdown(report);
  t.csv(dir / "figure_2_14_speedups.csv");
}

// Every replayed step of every configuration, for Figures 2.13 and 2.14.
void Bench::write_replay_steps() const {
  std::ofstream csv(dir / "replay_steps.csv");
  csv << std::setprecision(9)
      << "config,engine,threads,step,time,bodies,pairs,phase,seconds,seconds_rays,seconds_prepare,seconds_full,"
         "seconds_iterative,seconds_gather,pairs_full,pairs_iterative,rays,colliding,contacts,depth_sum,judged,deep,"
         "missed,false_rays,bytes_to_device,bytes_from_device\n";
  for (const ReplayRun& r : runs)
    for (uint64_t i = 0; i < r.steps.size(); ++i) {
      const ReplayStep& s = r.steps[i];
      if (!s.ran) continue;
      const sim::RecordedStep& rec = recording.steps()[i];
      DeviceWork devices;
      for (const DeviceWork& d : s.devices) devices += d;
      csv << '"' << r.config.label << "\"," << r.engine_name << ',' << r.config.threads << ',' << i << ',' << rec.time
          << ',' << rec.bodies << ',' << s.pairs << ',' << phases.of(i) << ',' << s.seconds << ',' << s.seconds_rays()
          << ',' << s.seconds_prepare << ',' << s.seconds_full << ',' << s.seconds_iterative << ','
          << s.seconds_gather << ',' << s.pairs_full << ',' << s.pairs_iterative << ',' << s.counts.rays() << ','
          << s.colliding << ',' << s.contacts << ',' << s.depth_sum << ',' << s.judged << ',' << s.deep << ','
          << s.missed << ',' << s.false_rays << ',' << devices.bytes_to_device << ',' << devices.bytes_from_device << '\n';
    }
}

// The host's stages per step, rtcd's and GIMPACT's, for Figure 2.12.
void Bench::write_host_steps() const {
  std::ofstream host(dir / "host_steps.csv");
  host << std::setprecision(9) << "host,step,bodies,pairs,contacts,seconds_broad,seconds_narrow,seconds_solver,"
                                  "seconds_effects,seconds_total\n";
  for (uint64_t i = 0; i < host_steps; ++i) {
    const sim::RecordedStep& r = recording.steps()[i];
    host << "rtcd," << i << ',' << r.bodies << ',' << r.pairs << ',' << r.contacts << ',' << r.seconds_broad << ','
         << r.seconds_narrow << ',' << r.seconds_solver << ',' << r.seconds_effects << ',' << r.seconds_total << '\n';
  }
  for (const sim::StepRecord& r : gimpact_host)
    host << "GIMPACT," << r.step << ',' << r.bodies << ',' << r.pairs << ',' << r.contacts << ',' << r.seconds_broad
         << ',' << r.seconds_narrow << ',' << r.seconds_solver << ',' << r.seconds_effects << ',' << r.seconds_total
         << '\n';
}

void Bench::peers(std::ostream& report) const {
  // The steps both peers ran.
  std::vector<bool> sampled(steps, false);
  size_t sampled_count = 0;
  for (uint64_t i = 0; i < steps; ++i)
    sampled_count += sampled[i] = run_of("GIMPACT").steps[i].ran && run_of("FCL").steps[i].ran;
  Table t;
  t.header = {"narrow phase (" + std::to_string(sampled_count) + " sampled steps)",
              "median step (ms)", "peak step (ms)", "GIMPACT ÷ it, median", "FCL ÷ it, median", "GIMPACT ÷ it, peak",
              "FCL ÷ it, peak", "colliding pairs", "contacts"};
  const Stats g = stats(run_of("GIMPACT"), 0, steps, whole_of, &sampled);
  const Stats f = stats(run_of("FCL"), 0, steps, whole_of, &sampled);
  std::vector<std::string> labels = {"auto embree", "full embree", "GIMPACT", "FCL"};
  if (cores > 1) labels.insert(labels.begin() + 2, "auto embree, " + n_threads);
  for (const std::string& label : labels) {
    const ReplayRun& r = run_of(label);
    const Stats st = stats(r, 0, steps, whole_of, &sampled);
    size_t colliding = 0, contacts = 0;
    for (uint64_t i = 0; i < steps; ++i)
      if (sampled[i] && r.steps[i].ran) colliding += r.steps[i].colliding, contacts += r.steps[i].contacts;
    const bool peer = r.config.engine != Engine::ours;
    t.rows.push_back({label, ms(st.median), ms(st.peak), peer ? "" : ratio(g.median / st.median),
                      peer ? "" : ratio(f.median / st.median), peer ? "" : ratio(g.peak / st.peak),
                      peer ? "" : ratio(f.peak / st.peak), std::to_string(colliding), std::to_string(contacts)});
  }
  report << "## Peers on the replay: GIMPACT and FCL against rtcd, same poses, same pairs\n\n"
            "One thread each (rtcd on " << n_threads << " beside). Ratios of step times measured in the same run "
            "on the same sampled steps; the automatic mode ran every step and is timed on the sampled ones. "
            "GIMPACT: btGImpactMeshShape pairs through btGImpactCollisionAlgorithm (margin 0), every penetrating "
            "point. FCL: fcl::collide on BVHModel<OBBRSS> with every contact. Colliding pairs differ in meaning: "
            "rtcd counts a pair colliding when a vertex of one body is inside the other; GIMPACT when triangles "
            "interpenetrate; FCL when triangles intersect. Depths are not compared: GIMPACT's are per clipped "
            "triangle pair, FCL's per intersecting triangle pair, rtcd's per penetrating vertex along its ray.\n\n";
  t.markdown(report);
  t.csv(dir / "peers.csv");
}

void Bench::interpenetration_tables(std::ostream& report) const {
  write_simulations();
  table_2_3(report);
  table_2_4(report);
  projected_interpenetration(report);
  true_penetration(report);
}

// Every simulation's outcome, a row per variant and seed.
void Bench::write_simulations() const {
  std::ofstream csv(dir / "simulations.csv");
  csv << std::setprecision(9)
      << "table,variant,seed,interpenetration,projected_interpenetration,deepest,true_penetration,deepest_true,"
         "seconds,narrow_seconds,error\n";
  for (const Outcome& oc : outcomes)
    csv << oc.variant->table << ",\"" << oc.variant->label << "\"," << oc.seed << ',' << oc.result.interpenetration
        << ',' << oc.result.projected << ',' << oc.result.deepest << ',' << oc.result.true_penetration << ','
        << oc.result.deepest_true << ',' << oc.result.seconds << ',' << oc.result.narrow_seconds << ",\""
        << oc.result.error << "\"\n";
}

std::vector<double> Bench::over_seeds(const std::string& label, double SimOutcome::*figure) const {
  std::vector<double> v;
  for (const Outcome& oc : outcomes)
    if (oc.variant->label == label && oc.result.error.empty()) v.push_back(oc.result.*figure);
  return v;
}

void Bench::table_2_3(std::ostream& report) const {
  const auto nop = over_seeds("no predictive rays"), p = over_seeds("predictive rays"),
             ps = over_seeds("predictive rays + speculative contacts");
  report << "## Table 2.3: cumulative interpenetration at the end, with and without predictive rays\n\n"
            "Simulations (the contacts feed back), "
         << o.seeds << " seeds each (mean, and min – max): the summed depth of every penetrating ray of every "
            "overlapping pair, traced in full without predictive rays, after the last step.\n\n";
  Table t3;
  t3.header = {"", "no predictive rays", "predictive rays", "decrease", "predictive + speculative contacts",
               "decrease"};
  t3.rows.push_back({scene.name, spread(nop), spread(p), decrease(nop, p), spread(ps), decrease(nop, ps)});
  t3.markdown(report);
  t3.csv(dir / "table_2_3.csv");
}

void Bench::table_2_4(std::ostream& report) const {
  const auto std_c = over_seeds("standard constraints"), proj = over_seeds("projected constraints");
  report << "## Table 2.4: standard against projected constraints\n\n"
         << "Both with predictive rays; first as the scene runs, then as the thesis measured it.\n\n";
  Table t4;
  t4.header = {"", "standard constraints", "projected constraints", "decrease"};
  t4.rows.push_back({scene.name + " (" + (speculative ? "speculative contacts, " : "") +
                         std::to_string(scene.points_per_pair) + " points per pair)",
                     spread(std_c), spread(proj), decrease(std_c, proj)});
  const auto thesis_std = over_seeds("standard constraints, as the thesis ran"),
             thesis_proj = over_seeds("projected constraints, as the thesis ran");
  t4.rows.push_back({scene.name + " as the thesis ran (no speculative contacts, " +
                         std::to_string(kThesisPointsPerPair) + " points per pair)",
                     spread(thesis_std), spread(thesis_proj), decrease(thesis_std, thesis_proj)});
  t4.markdown(report);
  t4.csv(dir / "table_2_4.csv");
}

// The summed projected depth: what the solver is asked to undo.
void Bench::projected_interpenetration(std::ostream& report) const {
  report << "The same simulations in summed projected depth (depth times the cosine between ray and normal), "
            "beside the summed ray depth above: a grazing ray is long but asks the solver for little.\n\n";
  Table tp;
  tp.header = {"", "no predictive rays", "predictive rays", "predictive + speculative contacts",
               "standard constraints", "projected constraints", "standard (as the thesis ran)",
               "projected (as the thesis ran)"};
  const auto projected = [&](const std::string& label) { return spread(over_seeds(label, &SimOutcome::projected)); };
  tp.rows.push_back({scene.name, projected("no predictive rays"), projected("predictive rays"),
                     projected("predictive rays + speculative contacts"), projected("standard constraints"),
                     projected("projected constraints"), projected("standard constraints, as the thesis ran"),
                     projected("projected constraints, as the thesis ran")});
  tp.markdown(report);
  tp.csv(dir / "projected_interpenetration.csv");
}

void Bench::true_penetration(std::ostream& report) const {
  report << "## True penetration at the end\n\n"
            "The same passes' contacts measured to the target's nearest surface (Config::nearest_surface): the "
            "summed and the deepest true penetration, whatever contacts the simulation ran with; the last row "
            "runs the defaults, contacts measured to the nearest surface.\n\n";
  Table tt;
  tt.header = {"variant", "summed true penetration", "deepest true penetration"};
  for (const std::string label :
       {"no predictive rays", "predictive rays", "predictive rays + speculative contacts", "standard constraints",
        "projected constraints", "standard constraints, as the thesis ran", "projected constraints, as the thesis ran",
        kNearestVariant})
    tt.rows.push_back({label, spread(over_seeds(label, &SimOutcome::true_penetration)),
                       spread(over_seeds(label, &SimOutcome::deepest_true))});
  tt.markdown(report);
  tt.csv(dir / "true_penetration.csv");
}

void Bench::accuracy_curve(std::ostream& report) const {
  // Phase C, or the last tenth of the steps in a scene that never settles.
  const bool settles = phases.c_begin < phases.end;
  const uint64_t settled = settles ? phases.c_begin : steps - std::max<uint64_t>(1, steps / 10);
  Table a;
  a.header = {"configuration", "mean ray time, settled (ms)", "mean detect, settled (ms)",
              "missed rays (judged steps)", "interpenetration at the end (simulated)"};
  for (const ReplayRun& r : runs) {
    if (r.config.engine != Engine::ours || r.config.threads != 1) continue;
    double interpenetration = NAN;
    for (const Outcome& oc : outcomes)
      if (oc.variant->table == "accuracy" && oc.variant->label == r.config.label)
        interpenetration = oc.result.interpenetration;
    a.rows.push_back({r.config.label, ms(stats(r, settled, phases.end, rays_of).mean),
                      ms(stats(r, settled, phases.end, whole_of).mean), percent(judged(r).rate()),
                      fixed(interpenetration, 4)});
  }
  report << "## Accuracy against time on the scene\n\nEach configuration replayed (time when settled, missed rays "
            "judged by the exact reference) and simulated from the scene's seed (interpenetration at the end). "
            "Settled: "
         << (settles ? "phase C, steps [" + std::to_string(settled) + ", " + std::to_string(steps) + ")"
                     : "the scene never settles (phase C is empty), so the last tenth of the steps, [" +
                           std::to_string(settled) + ", " + std::to_string(steps) + ")")
         << "; a configuration that stopped for its budget has no time there.\n\n";
  a.markdown(report);
  a.csv(dir / "accuracy.csv");
  report << "![accuracy against time](accuracy.png)\n\n";
}

}  // namespace

std::string run_bench(const BenchOptions& o) { return Bench(o).run(); }

}  // namespace rtcd::experiments
