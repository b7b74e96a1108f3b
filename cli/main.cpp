// The `rtcd` command: list backends, query a pair of shapes (one pose or a
// sequence of poses carrying the pair state across steps), validate a
// backend against the oracles.
#include <algorithm>
#include <iostream>

#include <CLI/CLI.hpp>

#include "knob_options.hpp"
#include "mpi_ranks.hpp"
#include "rtcd/app/bench.hpp"
#include "rtcd/app/check.hpp"
#include "rtcd/app/inputs.hpp"
#include "rtcd/app/knobs.hpp"
#include "rtcd/app/replay.hpp"
#include "rtcd/app/view.hpp"
#include "rtcd/app/report.hpp"
#include "rtcd/app/run.hpp"
#include "rtcd/app/validate.hpp"
#include "rtcd/backend.hpp"
#include "rtcd/error.hpp"
#include "rtcd/narrow_phase.hpp"
#include "rtcd/validation/families.hpp"

namespace {

constexpr int kBadInput = 2;

struct QueryOptions {
  std::string a, b, pose_a, pose_b, backend = "auto", mode = "auto", sequence;
  bool json = false;
  rtcd::MeshOptions mesh_options;
  rtcd::app::Knobs knobs;
  double sampling = 0.0;
};

int run_backends(bool json) {
  const auto list = rtcd::available_backends();
  if (json) {
    nlohmann::json out = nlohmann::json::array();
    for (const auto& b : list) out.push_back({{"name", b.name}, {"usable", b.usable}, {"devices", b.detail}});
    std::cout << out.dump(2) << '\n';
  } else {
    for (const auto& b : list) std::cout << b.name << (b.usable ? "  " : "  (unusable)  ") << b.detail << '\n';
  }
  return 0;
}

// `rtcd validate`, on every rank of the MPI job when mpirun started it. A
// rank that fails ends the whole job: the others would wait for it.
int run_validate_on_ranks(const rtcd::app::ValidateOptions& v) {
  const auto ranks = rtcd::cli::mpi_ranks_if_launched();
  if (!ranks || ranks->size() == 1) return rtcd::app::run_validate(v, ranks ? *ranks : rtcd::app::one_process());
  try {
    return rtcd::app::run_validate(v, *ranks);
  } catch (const std::exception& e) {
    std::cerr << "rtcd: rank " << ranks->rank() << ": " << e.what() << '\n';
    rtcd::cli::abort_job(dynamic_cast<const rtcd::Error*>(&e) ? kBadInput : 1);
  }
}

int run_query(const QueryOptions& o) {
  rtcd::Config config = o.knobs.config();
  config.mode = rtcd::parse_mode(o.mode);
  config.validate();

  std::vector<rtcd::app::SequenceStep> steps;
  if (!o.sequence.empty()) {
    if (!o.pose_a.empty() || !o.pose_b.empty()) throw rtcd::UsageError("--sequence replaces --pose-a and --pose-b");
    steps = rtcd::app::read_sequence(o.sequence);
  } else {
    rtcd::app::SequenceStep s;
    if (!o.pose_a.empty()) s.a = rtcd::app::parse_pose(o.pose_a, "--pose-a");
    if (!o.pose_b.empty()) s.b = rtcd::app::parse_pose(o.pose_b, "--pose-b");
    steps.push_back(s);
  }
  auto shape_a = rtcd::app::parse_shape(o.a, o.sampling, o.mesh_options);
  auto shape_b = o.b == o.a ? shape_a : rtcd::app::parse_shape(o.b, o.sampling, o.mesh_options);
  const double ratio = std::max(shape_a->radius(), shape_b->radius()) / std::min(shape_a->radius(), shape_b->radius());
  if (ratio > rtcd::kMaxSizeRatio)
    std::cerr << "rtcd: warning: the bodies' sizes differ by " << ratio << " (supported up to " << rtcd::kMaxSizeRatio
              << "): penetrations shallower than 1e-6 of the larger body may be missed or false\n";

  auto narrow = rtcd::make_narrow_phase(o.backend, config);
  const rtcd::ShapeId sa = narrow->add_shape(shape_a);
  const rtcd::ShapeId sb = shape_b == shape_a ? sa : narrow->add_shape(shape_b);
  const rtcd::BodyId a = narrow->add_body(sa, steps[0].a);
  const rtcd::BodyId b = narrow->add_body(sb, steps[0].b);
  const rtcd::BodyPair pair{a, b};

  nlohmann::json all = nlohmann::json::array();
  for (size_t i = 0; i < steps.size(); ++i) {
    narrow->set_pose(a, steps[i].a);
    narrow->set_pose(b, steps[i].b);
    const rtcd::StepResult r = narrow->detect(std::span(&pair, 1));
    if (o.json) {
      all.push_back(rtcd::app::to_json(r));
    } else {
      if (steps.size() > 1) std::cout << "step " << i << ":\n";
      if (i == 0) std::cout << "backend: " << narrow->name() << "\n";
      rtcd::app::print_table(std::cout, r);
    }
  }
  if (o.json) std::cout << (o.sequence.empty() ? all[0] : all).dump(2) << '\n';
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"rtcd: ray-traced narrow-phase collision detection for concave meshes"};
  app.set_version_flag("--version", std::string("rtcd ") + RTCD_VERSION);
  app.require_subcommand(1);

  bool backends_json = false;
  auto* backends = app.add_subcommand("backends", "List the backends built into rtcd and their devices");
  backends->add_flag("--json", backends_json, "Print JSON");
  auto* knobs = app.add_subcommand("knobs", "The narrow phase's knobs (range, default, meaning, cost) and step counters, as Markdown");

  QueryOptions q;
  auto* query = app.add_subcommand("query", "Detect the contacts between two shapes");
  query->add_option("A", q.a, "Mesh file (.obj .off .ply .stl), sphere:R or box:HX,HY,HZ")->required();
  query->add_option("B", q.b, "Mesh file, sphere:R or box:HX,HY,HZ")->required();
  query->add_option("--pose-a", q.pose_a, "Pose of A: \"tx ty tz qw qx qy qz\" (default identity)");
  query->add_option("--pose-b", q.pose_b, "Pose of B: \"tx ty tz qw qx qy qz\" (default identity)");
  query->add_option("--sequence", q.sequence, "JSON array of {\"pose_a\": [7], \"pose_b\": [7]} steps");
  query->add_option("--backend", q.backend, "basic, embree, opencl, opencl-basic (then :gpu, :cpu, :devices=0,1, :layout=grid|compact) or auto");
  query->add_option("--mode", q.mode, "full, iterative or auto");
  rtcd::cli::add_knobs(*query, q.knobs);
  query->add_option("--sampling", q.sampling, "Extra ray origins per unit area on sphere and box sources");
  query->add_flag("--allow-zero-area", q.mesh_options.allow_zero_area, "Keep zero-area triangles (never hit)");
  query->add_flag("--weld", q.mesh_options.weld,
                  "Join vertices at identical positions (triangle soups); ids then count the joined vertices");
  query->add_flag("--json", q.json, "Print JSON");

  rtcd::app::CheckOptions c;
  auto* check = app.add_subcommand(
      "check", "Check mesh files: topology, orientation, self-intersections, sizes. Exit 0 fit, 1 defect, 2 unreadable");
  check->add_option("MESH", c.files, "Mesh files (.obj .off .ply .stl)")->required();
  check->add_flag("--json", c.json, "Print JSON");
  check->add_flag("--weld", c.weld, "Join vertices at identical positions before checking");

  rtcd::app::ValidateOptions v;
  bool sweep = false;
  auto* validate = app.add_subcommand(
      "validate", "Judge a backend on random pairs against the exact reference, FCL, GIMPACT and libccd");
  validate->add_option("--backend", v.backend, "basic, embree, opencl[-basic][:...] or auto (default: every usable backend)");
  std::string families;
  for (const auto& name : rtcd::validation::family_names()) families += (families.empty() ? "" : ", ") + name;
  validate->add_option("--family", v.family, families + " (default: all)");
  validate->add_option("--pairs", v.pairs, "Random pairs per family")->check(CLI::Range(size_t(1), size_t(10'000'000)));
  validate->add_option("--seed", v.seed, "Seed of the random poses");
  validate->add_option("--mode", v.mode, "full, or iterative (a full step, then 4 steps of a fixed motion, the last judged)");
  rtcd::cli::add_knobs(*validate, v.knobs);
  validate->add_flag("--no-oracles", v.no_oracles, "Only the exact reference (skip FCL, GIMPACT, libccd)");
  validate->add_flag("--json", v.json, "Print JSON");
  validate->add_flag("--sweep", sweep, "Sweep the accuracy knobs; write CSV (see --csv)");
  validate->add_option("--csv", v.sweep_csv, "Where --sweep writes its CSV (default: standard output)");
  validate->add_option("--campaign", v.campaign,
                       "Keep every finished shard of pairs in this directory; started again with it, run only the "
                       "shards it lacks (exit 3 while some are left)");
  validate->add_option("--shard-pairs", v.shard_pairs, "Pairs per shard of a campaign (default: 100)")
      ->check(CLI::Range(size_t(1), size_t(10'000'000)));
  validate->add_option("--hours", v.hours, "Start no shard of a campaign after this many hours (default: no limit)")
      ->check(CLI::NonNegativeNumber);

  rtcd::app::RunOptions r;
  uint64_t run_steps = 0;
  auto* run = app.add_subcommand("run", "Simulate a scene on Bullet with rtcd's narrow phase (default: a small avalanche)");
  run->add_option("SCENE", r.scene, "Scene file (data/scenes/*.json; schema in docs/scenes.md)");
  run->add_option("--backend", r.backend, "Narrow-phase backend (overrides the scene's)");
  run->add_option("--steps", run_steps, "Steps to run (overrides the scene's duration)")
      ->check(CLI::Range(uint64_t(1), uint64_t(1'000'000'000)));
  run->add_option("--threads", r.threads, "Worker threads (default: all cores)")->check(CLI::Range(1, 4096));
  run->add_option("--out", r.out, "Output folder (default: runs/<scene>-<timestamp>/)");
  run->add_flag("--no-plots", r.no_plots, "Skip the PNG plots");
  run->add_flag("--full-rays", r.full_rays,
                "Snapshots draw each contact ray at its whole depth (default: the solver's segment, projected depth "
                "along the normal)");
  run->add_option("--record", r.record, "Also write the run's recording here, for rtcd replay and rtcd bench --replay");
  run->add_flag("--view", r.view, "Also record the run and write its page into view/ (rtcd view)");

  rtcd::experiments::BenchOptions bo;
  bool bench_no_plots = false;
  auto* bench = app.add_subcommand(
      "bench", "The thesis' experiments on a scene: record, replay through rtcd, GIMPACT and FCL, tables and plots");
  bench->add_option("SCENE", bo.scene, "avalanche, stream, their _small versions, or a scene file");
  bench->add_option("--replay", bo.replay, "Replay this recording (recording.rtcdrec of an earlier bench) instead");
  bench->add_option("--out", bo.out, "Output folder (default: runs/bench-<scene>/)");
  bench->add_option("--full-every", bo.full_every, "Replay full tracing with the basic tracer on every k-th step (default: steps / 60)");
  bench->add_option("--peers-every", bo.peers_every, "Replay GIMPACT and FCL on every k-th step (default: steps / 60)");
  bench->add_option("--judge-every", bo.judge_every, "Judge rays by the exact reference every k-th step (default: steps / 20)");
  bench->add_option("--gimpact-host-steps", bo.gimpact_host_steps, "Steps of the GIMPACT-hosted simulation (default: 600)")
      ->check(CLI::Range(uint64_t(1), uint64_t(1'000'000'000)));
  bench->add_option("--budget", bo.budget_seconds, "Seconds a replayed configuration may take in all before it stops")
      ->check(CLI::Range(1.0, 1e9));
  bench->add_option("--steps", bo.steps, "Simulate this many steps instead of the scene's duration")
      ->check(CLI::Range(uint64_t(1), uint64_t(1'000'000'000)));
  bench->add_option("--seeds", bo.seeds, "Seeds per interpenetration variant")->check(CLI::Range(1, 100));
  bench->add_flag("--no-plots", bench_no_plots, "Skip the PNG plots");

  rtcd::app::ReplayOptions ro;
  auto* replay = app.add_subcommand(
      "replay", "Replay a recording (from rtcd bench) through one narrow-phase configuration: time per stage and phase");
  replay->add_option("RECORDING", ro.recording, "recording.rtcdrec")->required();
  auto* peer = replay->add_option("--peer", ro.peer,
                                  "gimpact or fcl: that library on the same steps instead of rtcd, one thread (the peers "
                                  "of rtcd bench, on every step)");
  replay->add_option("--backend", ro.backend, "basic, embree, opencl[-basic][:...] or auto (default: embree)")->excludes(peer);
  replay->add_option("--mode", ro.mode, "full, iterative or auto (default: auto)")->excludes(peer);
  replay->add_option("--threads", ro.threads, "Worker threads (default: 1)")->check(CLI::Range(1, 4096))->excludes(peer);
  replay->add_option("--judge-every", ro.judge_every, "Judge rays by the exact reference every k-th step (default: never)");
  replay->add_option("--last", ro.last, "Also sum the recording's last N steps, in a row of their own (default: none)")
      ->check(CLI::Range(uint64_t(1), uint64_t(1'000'000'000)));
  rtcd::cli::add_knobs(*replay, ro.knobs);

  rtcd::app::ViewOptions vo;
  auto* view = app.add_subcommand(
      "view", "A recording to watch: a page that opens from file:// (bodies, contacts, a timeline), or one glTF 2.0 binary");
  view->add_option("RECORDING", vo.input, "recording.rtcdrec (rtcd run --record, rtcd bench), or a run folder holding one (rtcd run --view)")
      ->required();
  view->add_option("--out", vo.out, "The page's folder (default: view/ beside the recording)");
  view->add_option("--gltf", vo.gltf, "Write this .glb instead of a page (Blender and any glTF viewer open it)");
  bool view_serve = false;
  int view_port = 8000;
  view->add_flag("--serve", view_serve, "Then serve the page on 127.0.0.1 until stopped (for large runs)");
  view->add_option("--port", view_port, "The port --serve listens on (default: 8000)")->check(CLI::Range(1, 65535));
  view->add_flag("!--no-contacts", vo.contacts, "Leave the contacts out (no replay of the recording)");
  view->add_option("--backend", vo.backend, "The narrow phase the contacts are replayed through (default: embree)");

  try {
    app.parse(argc, argv);
    if (*backends) return run_backends(backends_json);
    if (*knobs) {
      rtcd::app::print_knobs(std::cout);
      return 0;
    }
    if (*bench) {
      bo.command = "rtcd";
      for (int i = 1; i < argc; ++i) bo.command += std::string(" ") + argv[i];
      return rtcd::app::run_bench(bo, !bench_no_plots);
    }
    if (*run) {
      if (run_steps > 0) r.steps = run_steps;
      return rtcd::app::run_scene(r);
    }
    if (*check) return rtcd::app::run_check(c);
    if (*replay) return rtcd::app::run_replay(ro);
    if (*view) {
      if (view_serve) vo.serve = view_port;
      return rtcd::app::run_view(vo);
    }
    if (*validate) {
      if (sweep && v.sweep_csv.empty()) v.sweep_csv = "-";
      if (!sweep && !v.sweep_csv.empty()) throw rtcd::UsageError("--csv needs --sweep");
      if (v.campaign.empty() && (validate->count("--shard-pairs") || validate->count("--hours")))
        throw rtcd::UsageError("--shard-pairs and --hours need --campaign");
      return run_validate_on_ranks(v);
    }
    return run_query(q);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForAllHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForVersion& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    std::cerr << "rtcd: " << e.what() << '\n';
    return kBadInput;
  } catch (const rtcd::Error& e) {
    std::cerr << "rtcd: " << e.what() << '\n';
    return kBadInput;
  } catch (const std::exception& e) {
    std::cerr << "rtcd: internal error: " << e.what() << '\n';
    return 1;
  }
}
