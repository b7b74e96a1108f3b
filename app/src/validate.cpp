// `rtcd validate` (see validate.hpp).
#include "rtcd/app/validate.hpp"

#include <algorithm>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <optional>

#include <nlohmann/json.hpp>

#include "campaign.hpp"
#include "commit.hpp"
#include "rtcd/backend.hpp"
#include "rtcd/backend_options.hpp"
#include "rtcd/error.hpp"
#include "rtcd/knobs_json.hpp"
#include "rtcd/narrow_phase.hpp"
#include "rtcd/validation/sweep.hpp"

namespace rtcd::app {
namespace {

void print_row(const validation::Summary& s) {
  auto ratio = [&](double oracle) { return s.time_ours > 0 && oracle > 0 ? oracle / s.time_ours : 0.0; };
  std::printf("%-10s %-6s %-9s %5zu %5.1f%% %7zu %8.2e %8.2e %5zu %6zu %6zu %8.1e %9.1f %8.1f", s.family.c_str(),
              s.backend.c_str(), to_string(s.mode), s.pairs, 100 * s.colliding_fraction(), s.deep, s.missed_rate(),
              s.missed_p99, s.false_rays, s.missed_pairs, s.false_pairs, s.max_relative_depth_error,
              1e6 * s.time_ours, 1e6 * s.time_exact);
  if (s.with_oracles)
    std::printf(" %6.2f%% %4zu/%-4zu %7zu %6.2f%% %8.1f %8.1f %8.1f  %5.2f %5.2f %5.2f", 100 * s.fcl_agreement(),
                s.fcl_blind_contained, s.contained, s.fcl_missed_pairs, 100 * s.gimpact_agreement(),
                1e6 * s.time_fcl, 1e6 * s.time_fcl_contacts, 1e6 * s.time_gimpact, ratio(s.time_fcl),
                ratio(s.time_fcl_contacts), ratio(s.time_gimpact));
  std::printf("\n");
  if (s.mode == validation::RunMode::iterative)
    std::printf("%-10s missed: %zu of %zu deep origins, %zu not tracked going into the judged step; per colliding "
                "pair p50 %.2e p90 %.2e p99 %.2e max %.2e; full steps %.2f%% of %zu motion steps; judged steps "
                "walked %zu, skipped on a certificate %zu\n",
                "", s.missed, s.deep, s.missed_untracked, s.missed_p50, s.missed_p90, s.missed_p99, s.missed_max,
                s.motion_steps ? 100.0 * double(s.full_steps) / double(s.motion_steps) : 0.0, s.motion_steps,
                s.iterative_pairs, s.certified_pairs);
  std::printf("%-10s truth: %zu contacts, %zu deeper than 1.25x their true penetration; solver depth / true "
              "p50 %.3f p99 %.3f max %.3f; push to nearest surface p50 %.1f deg p95 %.1f deg; %zu pairs whose "
              "deepest contact is under 0.8x their deepest point\n",
              "", s.truth_checked, s.over_reports, s.truth_ratio_p50, s.truth_ratio_p99, s.truth_ratio_max,
              s.push_angle_p50, s.push_angle_p95, s.under_reported_pairs);
  if (s.ccd_pairs)
    std::printf("%-10s libccd on %zu convex pairs: our largest projected depth / libccd depth = %.3f on average, "
                "mean |difference| %.4f; libccd %.1f us per pair\n",
                "", s.ccd_pairs, s.ccd_mean_ratio, s.ccd_mean_abs_difference, 1e6 * s.time_ccd);
}

std::vector<std::string> families_of(const ValidateOptions& o) {
  return o.family.empty() ? validation::family_names() : std::vector{o.family};
}

std::vector<std::string> backends_of(const ValidateOptions& o) {
  if (!o.backend.empty()) return {o.backend};
  std::vector<std::string> backends;
  for (const auto& b : available_backends())
    if (b.usable) backends.push_back(b.name);
  return backends;
}

// The arguments that make a run (and a campaign): what it runs, not where.
nlohmann::json run_arguments(const ValidateOptions& o, const std::vector<std::string>& families,
                                  const std::vector<std::string>& backends) {
  nlohmann::json kinds = nlohmann::json::array();
  for (const auto& b : backends) kinds.push_back(to_string(BackendOptions::parse(b).kind));
  return {{"families", families}, {"backends", kinds},           {"mode", o.mode},
          {"pairs", o.pairs},     {"seed", o.seed},              {"oracles", !o.no_oracles},
          {"knobs", knobs_json(o.knobs.config())}};
}

// Missed, false and under-reported pairs, each with what reproduces it.
nlohmann::json failing_pairs(const validation::Family& family, const validation::RunResult& r,
                             const validation::RunOptions& run) {
  nlohmann::json out = nlohmann::json::array();
  for (const auto& m : r.pairs)
    if (m.missed_pair() || m.false_pair() || m.under_reported)
      out.push_back({{"pair", m.index},
                     {"kind", m.missed_pair() ? "missed" : m.false_pair() ? "false" : "under-reported"},
                     {"replay", validation::describe(family, m, run)}});
  return out;
}

// Every run of `o` (families x backends), its shards where `runner` puts
// them; `on_result` sees each on the process that reports.
template <class OnResult>
void run_families(const ValidateOptions& o, const std::vector<std::string>& families,
                  const std::vector<std::string>& backends, const validation::ShardRunner& runner,
                  const OnResult& on_result) {
  validation::RunOptions run;
  run.config = o.knobs.config();
  run.mode = validation::parse_run_mode(o.mode);
  run.pairs = o.pairs;
  run.seed = o.seed;
  run.with_oracles = !o.no_oracles;
  for (const auto& family_name : families) {
    const validation::Family family = validation::make_family(family_name);
    warn_if_self_intersecting(*family.a, "family:" + family_name + ":a");
    warn_if_self_intersecting(*family.b, "family:" + family_name + ":b");
    for (const auto& backend : backends) {
      run.backend = backend;
      if (const auto r = validation::run_family(family, run, runner)) {
        nlohmann::json j = validation::to_json(r->summary);
        j["failing_pairs"] = failing_pairs(family, *r, run);
        on_result(r->summary, j);
      }
    }
  }
}

void print_header(bool oracles) {
  std::printf("%-10s %-6s %-9s %5s %6s %7s %8s %8s %5s %6s %6s %8s %9s %8s%s\n", "family", "backend", "mode", "pairs",
              "coll", "deep", "missed", "miss p99", "false", "mpairs", "fpairs", "depth re", "ours us", "exact us",
              oracles ? "  FCL agr FCL blind FCLmiss GIM agr   FCL us  FCLc us   GIM us   xFCL xFCLc  xGIM" : "");
}

void print_failing(const nlohmann::json& failing) {
  constexpr size_t kShown = 20;
  for (size_t i = 0; i < std::min(kShown, failing.size()); ++i)
    std::printf("%-10s %s pair: %s\n", "", failing[i]["kind"].get<std::string>().c_str(),
                failing[i]["replay"].get<std::string>().c_str());
  if (failing.size() > kShown) std::printf("%-10s ... and %zu more (--json lists them all)\n", "", failing.size() - kShown);
}

int run_sweep(const ValidateOptions& o, const std::vector<std::string>& families,
              const std::vector<std::string>& backends, const Ranks& ranks) {
  if (families.size() != 1 || backends.size() != 1) throw UsageError("--sweep needs one --family and one --backend");
  if (!o.campaign.empty()) throw UsageError("--sweep does not run as a campaign");
  const SpreadShards runner(ranks, nullptr);
  const auto points = validation::sweep(validation::make_family(families[0]), backends[0], o.pairs, o.seed, &runner);
  if (!ranks.reports()) return 0;
  if (o.sweep_csv == "-") {
    validation::write_csv(std::cout, points);
  } else {
    std::ofstream out(o.sweep_csv);
    if (!out) throw UsageError("cannot write '" + o.sweep_csv + "'");
    validation::write_csv(out, points);
    std::cerr << "wrote " << points.size() << " sweep points to " << o.sweep_csv << '\n';
  }
  return 0;
}

}  // namespace

nlohmann::json validate_json(const ValidateOptions& o) {
  nlohmann::json all = nlohmann::json::array();
  const SpreadShards runner(one_process(), nullptr);
  run_families(o, families_of(o), backends_of(o), runner,
               [&](const validation::Summary&, const nlohmann::json& j) { all.push_back(j); });
  return all;
}

int run_validate(const ValidateOptions& o, const Ranks& ranks) {
  const std::vector<std::string> families = families_of(o), backends = backends_of(o);
  if (!o.sweep_csv.empty()) return run_sweep(o, families, backends, ranks);

  const nlohmann::json arguments = run_arguments(o, families, backends);
  // Every rank must run the same runs in the same order (each run gathers
  // from all): a backend usable on some ranks only would leave them waiting.
  if (const std::string mine = arguments.dump(), first = ranks.broadcast(mine); first != mine)
    throw UsageError("rank " + std::to_string(ranks.rank()) + " would run " + mine + ", rank 0 " + first +
                     ": give every rank the same arguments, and name the backends where some are not usable on "
                     "every machine");
  std::optional<Campaign> campaign;
  if (!o.campaign.empty()) campaign.emplace(o.campaign, arguments, o.shard_pairs, o.hours, ranks);
  const SpreadShards runner(ranks, campaign ? &*campaign : nullptr);
  nlohmann::json all = nlohmann::json::array();
  if (!o.json && ranks.reports()) print_header(!o.no_oracles);
  run_families(o, families, backends, runner, [&](const validation::Summary& s, const nlohmann::json& j) {
    all.push_back(j);
    if (o.json) return;
    print_row(s);  // each row as soon as its run is done
    print_failing(j["failing_pairs"]);
    std::fflush(stdout);
  });
  if (!ranks.reports()) return 0;
  if (runner.unfinished()) {
    std::fprintf(stderr, "rtcd: the campaign in '%s' stopped after %g hours with shards left: start it again with "
                 "the same arguments to finish it\n", o.campaign.c_str(), o.hours);
    return kCampaignUnfinished;
  }
  if (campaign) {
    campaign->write_report({{"commit", kCommit}, {"runs", all}});
    if (!o.json) std::printf("campaign complete: %s\n", (campaign->dir() / "report.json").c_str());
  }
  if (o.json) std::cout << all.dump(2) << '\n';
  return 0;
}

}  // namespace rtcd::app
