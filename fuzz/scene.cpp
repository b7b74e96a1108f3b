// libFuzzer harness: scene files through the scene loader, then a few steps
// of the simulation. File access is stubbed (every mesh path "exists" and is
// simulated as a box of its scale), bodies and steps are capped, pictures are
// tiny. What a bad scene file may cause, and nothing else, ends an input:
// SceneError from the loader (the one rejection), and SimulationError from a
// step (a blow-up, named: a scene can ask for one, a body of 1e-40 kg).
// Any other exception, from building the simulation or from a step, is a
// finding: the loader accepted a scene the simulation cannot run, or the
// library failed on its own. A stage whose effect is not listed must do no
// work, and every pose after a step must be finite.
#include <cmath>
#include <cstdint>
#include <string>

#include "invariants.hpp"
#include "rtcd/error.hpp"
#include "rtcd/sim/simulation.hpp"

namespace {

using rtcd::fuzz::require;
using rtcd::sim::Effect;

void run(rtcd::sim::Scene scene) {
  for (auto& b : scene.bodies) {
    if (!b.mesh.empty()) {
      b.mesh.clear();
      b.box = Eigen::Vector3d::Constant(0.5 * b.scale);
    }
    if (b.blob) b.blob->triangles = std::min<uint32_t>(b.blob->triangles, 200);  // keep each input fast
  }
  scene.steps = std::min<uint64_t>(scene.steps, 4);
  scene.snapshot_width = std::min(scene.snapshot_width, 32);
  scene.snapshot_height = std::min(scene.snapshot_height, 32);
  rtcd::sim::Simulation sim(scene, "basic");
  for (uint64_t i = 0; i < scene.steps; ++i) {
    sim.step();
    for (const auto& b : sim.bodies()) require(b.pose.position.allFinite() && b.pose.orientation.coeffs().allFinite(), "non-finite pose after a step");
    if (scene.has(Effect::snapshots) && i == 0) {
      const rtcd::sim::Image image = sim.snapshot(scene.snapshot_width, scene.snapshot_height);
      require(image.rgb.size() == size_t(3 * image.width * image.height), "snapshot size");
    }
  }
  const auto& c = sim.counters();
  require(scene.has(Effect::gravity) || c.gravity_forces == 0, "gravity applied unlisted");
  require(scene.has(Effect::contacts) || c.narrow_phase_batches == 0, "narrow phase ran without contacts");
  // Once a sub-step (solver.substeps).
  require(!scene.has(Effect::contacts) || c.narrow_phase_batches == scene.steps * scene.solver_substeps,
          "narrow phase skipped a sub-step");
  require(scene.has(Effect::friction) || c.friction_points == 0, "points with friction, unlisted");
  require(scene.has(Effect::restitution) || c.restitution_points == 0, "points with restitution, unlisted");
  require(scene.has(Effect::speculative) || c.speculative_points == 0, "speculative points, unlisted");
  require(scene.has(Effect::interpenetration) || c.interpenetration_passes == 0, "interpenetration ran unlisted");
  require(c.steps == scene.steps, "steps miscounted");
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  rtcd::sim::SceneLimits limits;
  limits.max_bodies = 16;
  limits.max_steps = 1'000'000;
  limits.file_exists = [](const std::string&) { return true; };
  rtcd::sim::Scene scene;
  try {
    scene = rtcd::sim::parse_scene(std::string(reinterpret_cast<const char*>(data), size), "fuzz.json", limits);
  } catch (const rtcd::sim::SceneError&) {
    return 0;
  }
  try {
    run(std::move(scene));
  } catch (const rtcd::sim::SimulationError&) {
  } catch (const std::exception& e) {
    rtcd::fuzz::violated(std::string("a loaded scene threw: ") + e.what());
  }
  return 0;
}
