// A scene simulated on Bullet with rtcd's narrow phase: the step is
// assembled from the scene's effects alone, each stage counted and timed.
#pragma once

#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "rtcd/narrow_phase.hpp"
#include "rtcd/sim/render.hpp"
#include "rtcd/sim/scene.hpp"

namespace rtcd::sim {

// A simulation that blew up: the message names the step and the body.
class SimulationError : public Error {
 public:
  using Error::Error;
};

// What each stage did, counted where it does it (not where the effect is
// looked up): a stage whose effect is not listed stays at 0, and so does
// one that had nothing to do (friction without contact points).
struct StageCounters {
  uint64_t steps = 0;
  uint64_t gravity_forces = 0;        // gravity applied to a dynamic body, once per body and step
  uint64_t narrow_phase_batches = 0;  // collision batches a narrow phase answered (rtcd's or GIMPACT)
  uint64_t friction_points = 0;       // points handed to the solver with a friction coefficient > 0
  uint64_t restitution_points = 0;    // touching points handed to the solver with restitution > 0
  uint64_t speculative_points = 0;    // points handed to the solver with a gap (from predictive rays)
  uint64_t entry_pushes = 0;          // contacts that pushed their pair's entry way (DispatcherOptions::keep_entry_direction)
  uint64_t interpenetration_passes = 0;
  uint64_t snapshots = 0;
};

// What one step did and cost.
struct StepRecord {
  uint64_t step = 0;
  double time = 0;  // simulated time at the end of the step
  size_t bodies = 0;
  double seconds_broad = 0, seconds_narrow = 0, seconds_solver = 0, seconds_effects = 0, seconds_total = 0;
  size_t pairs = 0, pairs_full = 0, pairs_iterative = 0;
  RayCounts rays;  // the narrow phase's, as it counted them (zero under GIMPACT)
  size_t contacts = 0, predictive = 0, solver_points = 0, speculative_points = 0;
  size_t ground_contacts = 0;  // contacts between a body and the ground
  std::vector<DeviceWork> devices;  // what each device of the backend did (empty on the CPU backends)
  std::string cpu_fallback;         // why the step's rays ran on the CPU instead of the devices; empty: they did not
  double kinetic_energy = 0;
  // Set on the steps the interpenetration pass ran (else negative).
  double interpenetration = -1;  // summed depth of every penetrating ray (the thesis' figure)
  double projected = -1;         // summed projected depth: what the solver is asked to undo
  double deepest = -1;           // the largest single depth, projected
  // The same pass's contacts measured to the target's nearest surface
  // (Config::nearest_surface): the true penetration, summed and deepest.
  double true_penetration = -1;
  double deepest_true = -1;
  // Pairs deeper than 2% of their smaller body's size (its bounding
  // diameter), and the longest any has been held so, in steps (passes in a
  // row times the pass's period).
  size_t deep_pairs = 0;
  uint64_t longest_deep_run = 0;
  BodyPair longest_deep_pair;  // the pair held so, numbered as Simulation::bodies() (kGround: the ground)
  // The deepest body in the ground: its true penetration over its size
  // (0 with no ground contact; negative where the pass did not run).
  double ground_depth_fraction = -1;
  size_t interpenetration_pairs = 0;
};

struct BodyState {
  std::string label;  // "bodies[i]#k" or the spec's name with #k
  Pose pose;          // the shape's frame (the mesh file's frame), world
  Eigen::Vector3d linear_velocity = Eigen::Vector3d::Zero(), angular_velocity = Eigen::Vector3d::Zero();
  bool is_static = false;
  double mass = 0;
  size_t spec = 0;
};

// The shape of every entry of scene.bodies, in its file's frame, scaled;
// self-intersecting meshes add a line to `warnings`.
std::vector<std::shared_ptr<const Shape>> make_shapes(const Scene& scene, std::vector<std::string>* warnings = nullptr);

// The narrow phase named "gimpact" is Bullet's own: meshes collide as
// btGImpactMeshShape through btGImpactCollisionAlgorithm (Bullet's default
// margin), the reference the thesis measured the whole step against.
inline constexpr const char* kGimpact = "gimpact";

class Simulation {
 public:
  // backend overrides the scene's when not empty: a backend's string form
  // (BackendOptions::parse), or kGimpact. threads > 0: the narrow phase's
  // threads (BackendOptions::threads).
  explicit Simulation(const Scene& scene, const std::string& backend = "", int threads = 0);
  ~Simulation();
  Simulation(const Simulation&) = delete;
  Simulation& operator=(const Simulation&) = delete;

  // One step. Throws SimulationError when a pose turns non-finite.
  const StepRecord& step();
  const StepRecord& last() const;
  uint64_t steps_done() const;

  const Scene& scene() const;
  const StageCounters& counters() const;
  std::string backend() const;
  std::vector<std::string> devices() const;
  // The scene's bodies, in the order they were added (the ground is not
  // one): the numbering of contacts() and pairs().
  std::vector<BodyState> bodies() const;
  // The narrow phase's answer on the last step (contacts, predictive rays),
  // and the broad phase's pairs that step handed it, with bodies numbered
  // as bodies() numbers them: body k is bodies()[k]; the ground is kGround.
  static constexpr uint32_t kGround = UINT32_MAX;
  StepResult contacts() const;
  std::vector<BodyPair> pairs() const;
  // The same with the narrow phase's own BodyIds (the ground takes one;
  // body_kinds() and shape_poses() are numbered by them).
  const StepResult& last_narrow_phase() const;
  std::span<const BodyPair> last_pairs() const;

  // Every body the narrow phase knows, by BodyId, the ground included: the
  // index of its entry in scene.bodies (kGroundKind for the ground) and its
  // shape's world pose. Bodies are only ever added, so ids stay put.
  static constexpr uint32_t kGroundKind = UINT32_MAX;
  std::vector<uint32_t> body_kinds() const;
  void shape_poses(std::vector<Pose>& out) const;

  // A bit-exact digest of every body's pose and velocities.
  uint64_t state_hash() const;

  // Warnings met while loading (self-intersecting meshes), one line each.
  const std::vector<std::string>& warnings() const;

  // The scene now, drawn with the last step's contacts (the snapshots
  // stage): each as the segment a solver sees, from the point along the
  // contact normal by its projected depth; or, with `full_rays`, each ray
  // along its direction by its whole depth (grazing rays are long).
  Image snapshot(int width, int height, bool full_rays = false);

  // Runs the interpenetration pass now (also on the steps the scene asks
  // for); fills the last record's interpenetration fields.
  void measure_interpenetration();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace rtcd::sim
