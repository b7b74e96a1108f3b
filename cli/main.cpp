// The `rtcd` command: list backends, query a pair of shapes (one pose or a
// sequence of poses carrying the pair state across steps).
#include <iostream>

#include <CLI/CLI.hpp>

#include "inputs.hpp"
#include "report.hpp"
#include "rtcd/error.hpp"
#include "rtcd/narrow_phase.hpp"

namespace {

constexpr int kBadInput = 2;

struct QueryOptions {
  std::string a, b, pose_a, pose_b, backend = "auto", mode = "auto", sequence;
  bool no_predictive = false, json = false, allow_zero_area = false;
  uint32_t max_walk_steps = rtcd::Config{}.max_walk_steps;
  double displacement_threshold = rtcd::Config{}.displacement_threshold;
  double distance_extension = rtcd::Config{}.distance_extension;
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

int run_query(const QueryOptions& o) {
  rtcd::Config config;
  config.mode = rtcd::parse_mode(o.mode);
  config.predictive = !o.no_predictive;
  config.max_walk_steps = o.max_walk_steps;
  config.displacement_threshold = o.displacement_threshold;
  config.distance_extension = o.distance_extension;
  config.validate();

  std::vector<rtcd::cli::SequenceStep> steps;
  if (!o.sequence.empty()) {
    if (!o.pose_a.empty() || !o.pose_b.empty()) throw rtcd::UsageError("--sequence replaces --pose-a and --pose-b");
    steps = rtcd::cli::read_sequence(o.sequence);
  } else {
    rtcd::cli::SequenceStep s;
    if (!o.pose_a.empty()) s.a = rtcd::cli::parse_pose(o.pose_a, "--pose-a");
    if (!o.pose_b.empty()) s.b = rtcd::cli::parse_pose(o.pose_b, "--pose-b");
    steps.push_back(s);
  }
  auto shape_a = rtcd::cli::parse_shape(o.a, o.sampling, o.allow_zero_area);
  auto shape_b = o.b == o.a ? shape_a : rtcd::cli::parse_shape(o.b, o.sampling, o.allow_zero_area);

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
      all.push_back(rtcd::cli::to_json(r));
    } else {
      if (steps.size() > 1) std::cout << "step " << i << ":\n";
      if (i == 0) std::cout << "backend: " << narrow->name() << "\n";
      rtcd::cli::print_table(std::cout, r);
    }
  }
  if (o.json) std::cout << (o.sequence.empty() ? all[0] : all).dump(2) << '\n';
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"rtcd: ray-traced narrow-phase collision detection for concave meshes"};
  app.require_subcommand(1);

  bool backends_json = false;
  auto* backends = app.add_subcommand("backends", "List the backends built into rtcd and their devices");
  backends->add_flag("--json", backends_json, "Print JSON");

  QueryOptions q;
  auto* query = app.add_subcommand("query", "Detect the contacts between two shapes");
  query->add_option("A", q.a, "Mesh file (.obj .off .ply .stl), sphere:R or box:HX,HY,HZ")->required();
  query->add_option("B", q.b, "Mesh file, sphere:R or box:HX,HY,HZ")->required();
  query->add_option("--pose-a", q.pose_a, "Pose of A: \"tx ty tz qw qx qy qz\" (default identity)");
  query->add_option("--pose-b", q.pose_b, "Pose of B: \"tx ty tz qw qx qy qz\" (default identity)");
  query->add_option("--sequence", q.sequence, "JSON array of {\"pose_a\": [7], \"pose_b\": [7]} steps");
  query->add_option("--backend", q.backend, "basic, embree or auto");
  query->add_option("--mode", q.mode, "full, iterative or auto");
  query->add_flag("--no-predictive", q.no_predictive, "Do not cast predictive rays");
  query->add_option("--max-walk-steps", q.max_walk_steps, "Walk step limit [1, 1000000]");
  query->add_option("--displacement-threshold", q.displacement_threshold, "Equation 2.1 threshold");
  query->add_option("--distance-extension", q.distance_extension, "Predictive range and bounding-box growth");
  query->add_option("--sampling", q.sampling, "Extra ray origins per unit area on sphere and box sources");
  query->add_flag("--allow-zero-area", q.allow_zero_area, "Keep zero-area triangles (never hit)");
  query->add_flag("--json", q.json, "Print JSON");

  try {
    app.parse(argc, argv);
    if (*backends) return run_backends(backends_json);
    return run_query(q);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForAllHelp& e) {
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
