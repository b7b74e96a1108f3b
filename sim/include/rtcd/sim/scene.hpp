// Scene files (data/scenes/*.json; schema in docs/scenes.md): the bodies,
// the ground, the clock, the narrow phase and the effects a run simulates.
#pragma once

#include <array>
#include <cstdint>
#include <functional>
#include <optional>
#include <set>
#include <string>
#include <string_view>
#include <vector>

#include <Eigen/Core>

#include "rtcd/config.hpp"
#include "rtcd/error.hpp"
#include "rtcd/geometry.hpp"

namespace rtcd::sim {

// A scene that cannot be run; the message names the file and the key path.
class SceneError : public Error {
 public:
  using Error::Error;
};

// What a step may simulate. A step runs the stages of the listed effects only.
enum class Effect {
  gravity,           // bodies accelerate by the scene's gravity
  contacts,          // the narrow phase runs and the solver answers its contacts
  friction,          // Coulomb friction on contacts (needs contacts)
  restitution,       // bounce (needs contacts)
  predictive,        // predictive rays track vertices about to penetrate (needs contacts)
  speculative,       // predictive rays also go to the solver as speculative contacts (needs predictive)
  projected,         // push along the impacted triangle's normal by the projected depth (needs contacts)
  interpenetration,  // every K steps and at the end, sum the depth of every penetrating ray
  snapshots,         // rendered pictures at chosen steps
};
const char* to_string(Effect effect);
std::optional<Effect> parse_effect(std::string_view name);

// One entry of "bodies": its shape, how many, where they start.
struct BodySpec {
  std::string label;  // "bodies[i]" or its "name"
  // Exactly one shape: a mesh file (resolved against the scene's folder), a
  // generated concave blob, a sphere radius or box half extents.
  std::string mesh;
  double scale = 1.0;
  bool weld = false;
  struct Blob {
    uint32_t triangles = 902;  // even, 8 .. 2,000,000
    uint32_t seed = 1;
    double radius = 1.0;
  };
  std::optional<Blob> blob;
  std::optional<double> sphere;
  std::optional<Eigen::Vector3d> box;

  uint32_t count = 1;
  bool is_static = false;
  std::optional<double> mass, density;  // one of them for a dynamic body; density default 1000
  double friction = 0.5, restitution = 0.0;
  Eigen::Vector3d velocity = Eigen::Vector3d::Zero(), angular_velocity = Eigen::Vector3d::Zero();

  // Placement: a pose (count 1), a grid, or an emitter.
  Pose pose;
  struct Grid {
    std::array<uint32_t, 3> cells{1, 1, 1};
    Eigen::Vector3d origin = Eigen::Vector3d::Zero(), spacing = Eigen::Vector3d::Ones();
    double jitter = 0.0;  // uniform offset up to this much per axis (seeded)
    bool random_orientation = false;
  };
  std::optional<Grid> grid;
  // Bodies appear one at a time at `rate` per second from `start` on, from a
  // source moving on a horizontal circle (centre, radius, angular speed in
  // rad/s, angle angular_speed * t).
  struct Emitter {
    double rate = 1.0, start = 0.0;
    Eigen::Vector3d centre = Eigen::Vector3d::Zero();
    double radius = 0.0, angular_speed = 0.0;
    bool random_orientation = true;
  };
  std::optional<Emitter> emitter;
};

struct Ground {
  bool present = true;
  double height = 0.0;
  Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();
  double friction = 0.5, restitution = 0.0;
};

// The shortest step a scene may ask for. Bullet, in single precision, takes
// a step under its epsilon (about 1.2e-7 s) as no step at all: no contacts,
// no motion.
inline constexpr double kMinTimeStep = 1e-6;

struct Scene {
  std::string name;
  std::string path;  // the file, for messages and relative mesh paths
  double time_step = 1.0 / 60.0;
  uint64_t steps = 60;
  uint64_t seed = 1;
  bool sleeping = false;
  Eigen::Vector3d gravity{0.0, 0.0, -9.81};
  std::set<Effect> effects;

  std::string backend = "auto";
  Config narrow;                  // predictive and projected come from `effects`
  uint32_t points_per_pair = 8;   // contact points handed to the solver per pair
  uint32_t solver_iterations = 10;
  // Bullet steps each step in this many equal sub-steps, the narrow phase
  // and the solver once in each: a pile's weight is answered in smaller
  // slices of motion.
  uint32_t solver_substeps = 1;
  // The share of a contact's penetration the solver's split impulse
  // removes in a (sub-)step (Bullet's erp2, its default 0.2).
  double solver_erp2 = 0.2;

  uint32_t interpenetration_every = 10;
  std::vector<int64_t> snapshot_steps{-1};  // negative counts from the end (-1: the last step)
  int snapshot_width = 800, snapshot_height = 500;
  std::optional<Eigen::Vector3d> camera_eye, camera_target;

  Ground ground;
  std::vector<BodySpec> bodies;

  bool has(Effect e) const { return effects.contains(e); }
  double duration() const { return double(steps) * time_step; }
  uint64_t body_count() const;
};

// Caps on what a scene may ask for (the fuzz harness lowers them).
struct SceneLimits {
  uint64_t max_bodies = 100'000;
  uint64_t max_steps = 100'000'000;
  // Whether a mesh path names a readable file; the default asks the file system.
  std::function<bool(const std::string&)> file_exists;
};

// Throws SceneError naming the file and the key path ("bodies[2].mass").
Scene parse_scene(std::string_view json_text, const std::string& path, const SceneLimits& limits = {});
Scene load_scene(const std::string& path, const SceneLimits& limits = {});

}  // namespace rtcd::sim
