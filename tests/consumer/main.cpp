// A host that finds rtcd with find_package, includes the core's installed
// headers and nothing else, picks a backend without a string, and detects
// one contact (every installed header is compiled apart: run.cmake).
#include <cstdio>

#include <rtcd/backend.hpp>
#include <rtcd/backend_options.hpp>
#include <rtcd/config.hpp>
#include <rtcd/error.hpp>
#include <rtcd/geometry.hpp>
#include <rtcd/mesh.hpp>
#include <rtcd/mesh_check.hpp>
#include <rtcd/mesh_gen.hpp>
#include <rtcd/narrow_phase.hpp>
#include <rtcd/results.hpp>
#include <rtcd/shape.hpp>

int main() {
  // Meshes and the checker.
  const rtcd::Mesh cube = rtcd::gen::box({0.5, 0.5, 0.5});
  const rtcd::MeshCheck check = rtcd::check_mesh(cube.positions(), cube.triangles());
  if (!check.fit() || !check.closed) return 1;

  // Errors are typed.
  try {
    rtcd::Config bad;
    bad.distance_extension = -1;
    bad.validate();
    return 1;
  } catch (const rtcd::ConfigError&) {
  }

  rtcd::BackendOptions options;
  options.kind = rtcd::BackendKind::basic;
  options.threads = 1;
  for (const rtcd::BackendInfo& b : rtcd::available_backends()) std::printf("%s%s\n", b.name.c_str(), b.usable ? "" : " (unusable)");
  auto narrow = rtcd::make_narrow_phase(options);
  auto a = narrow->add_shape(std::make_shared<rtcd::Shape>(rtcd::Box{{0.5, 0.5, 0.5}}));
  auto b = narrow->add_shape(std::make_shared<rtcd::Shape>(rtcd::Box{{0.6, 0.6, 0.6}}));
  rtcd::Pose pb;
  pb.position = {1.0, 0.0, 0.0};
  const rtcd::BodyPair pair{narrow->add_body(a, {}), narrow->add_body(b, pb)};
  const rtcd::StepResult result = narrow->detect(std::span(&pair, 1));
  std::printf("%s: %zu contacts, %zu walk endings counted\n", narrow->name().c_str(), result.contacts.size(),
              result.stats.walk_endings.size());
  return result.contacts.size() == 4 && result.stats.walk_endings.size() == rtcd::kLineStatusCount ? 0 : 1;
}
