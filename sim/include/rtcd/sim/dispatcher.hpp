// A Bullet collision dispatcher that runs rtcd's narrow phase once per step
// over every broad-phase pair of linked bodies, as one batch, and writes the
// contacts into Bullet's manifolds. Pairs with an unlinked object go to
// Bullet's own algorithms, so a host can mix both in one world.
#pragma once

#include <limits>
#include <cstdint>
#include <span>
#include <unordered_map>
#include <vector>

#include <btBulletCollisionCommon.h>

#include "rtcd/narrow_phase.hpp"

namespace rtcd::sim {

struct DispatcherOptions {
  // Contact points handed to the solver per pair, in manifolds of four.
  // Range [1, 64]. Chosen: the deepest ray, then each next the one farthest
  // from those already chosen, so the points span the contact region.
  uint32_t points_per_pair = 8;
  // Predictive rays become speculative points (gap > 0) as well, with the
  // points the penetrating ones leave: first the gaps that close within the
  // step (the two points' approach along the normal covers the gap), then
  // the others.
  bool speculative = false;
  // Without these, points carry zero friction or restitution.
  bool friction = true;
  bool restitution = true;
  // A pair remembers the way its bodies met (their contacts' pushes while
  // the pair is shallower than a quarter of its thinner body's thickness);
  // deeper, a contact whose push turns against that way (the nearest
  // surface on the far side of a thin body pressed past its middle) pushes
  // the remembered way instead, by the same depth. Off: every push as the
  // narrow phase measured it.
  bool keep_entry_direction = true;
};

// What the dispatcher needs to know of a linked body.
struct BodyLink {
  BodyId id = 0;
  Pose shape_in_body;  // the shape's frame in the Bullet body's frame (its principal frame)
  double friction = 0.5, restitution = 0.0;
  double thickness = std::numeric_limits<double>::infinity();  // its thinnest extent (the ground: none)
};

class BatchDispatcher : public btCollisionDispatcher {
 public:
  BatchDispatcher(btCollisionConfiguration* configuration, NarrowPhase& narrow, DispatcherOptions options = {});
  ~BatchDispatcher() override;

  // Routes `object`'s pairs to the narrow phase (its user index becomes the
  // link's slot; the object must outlive the link).
  void link(btCollisionObject* object, const BodyLink& link);
  // Releases the object's manifolds; call before removing it from the world.
  void unlink(btCollisionObject* object);

  void dispatchAllCollisionPairs(btOverlappingPairCache* pairs, const btDispatcherInfo& info,
                                 btDispatcher* dispatcher) override;

  // The last batch: the narrow phase's answer, and what reached the solver.
  const StepResult& last_step() const { return result_; }
  // The pairs that batch handed the narrow phase, in its order.
  const std::vector<BodyPair>& last_pairs() const { return batch_pairs_; }
  struct Batch {
    uint64_t calls = 0;  // batches run so far
    size_t pairs = 0, points = 0, warm_started = 0;
    // Counted as each point is written, so they say what the solver got:
    // points with a friction coefficient, touching points with restitution,
    // speculative points (a gap, from predictive rays).
    size_t friction_points = 0, restitution_points = 0, speculative_points = 0;
    size_t entry_pushes = 0;  // contacts that pushed the pair's entry way instead (keep_entry_direction)
    double seconds_narrow = 0, seconds_manifolds = 0;
  };
  const Batch& last_batch() const { return batch_; }
  // The world pose of a linked object's shape frame.
  Pose shape_pose(const btCollisionObject* object) const;

 private:
  struct Slot {
    btCollisionObject* object = nullptr;
    BodyLink link;
    uint64_t posed = 0;  // the batch that last set its pose
  };
  // A contact or speculative point before it is written, in world coordinates.
  struct Candidate {
    Eigen::Vector3d on_a, on_b, normal_on_b;  // Bullet's convention: normal on B points toward A
    double distance;                           // < 0 penetrating, > 0 a speculative gap
    int side;
    // Which point it is, for warm starting across steps: a vertex id and
    // -1, an edge's two vertex ids, or -2 and -2 for a sphere's deepest point.
    int index0, index1;
  };
  struct PairManifolds {
    std::vector<btPersistentManifold*> manifolds;
    uint64_t seen = 0;  // the batch that last saw this pair
    // The way a moved out of b when the pair was last shallow, in b's shape
    // frame; zero: not known (DispatcherOptions::keep_entry_direction).
    Eigen::Vector3d entry_in_b = Eigen::Vector3d::Zero();
  };
  Slot* slot_of(const btCollisionObject* object);
  const Slot* slot_of(const btCollisionObject* object) const;
  // Appends to `chosen` the indices (from `offset` on) of up to `budget` of
  // the candidates, spread over them.
  void choose_spread(std::span<const Candidate> candidates, size_t offset, size_t budget, std::vector<size_t>& chosen);
  // Moves the gaps that close within the step to the front; returns how many.
  size_t closing_first(const btCollisionObject* a, const btCollisionObject* b);
  Eigen::Vector3d way_out(const PairResult& pair) const;
  void fill(const PairResult& pair, btCollisionObject* a, btCollisionObject* b, PairManifolds& held);
  void release(PairManifolds& held);

  NarrowPhase& narrow_;
  DispatcherOptions options_;
  std::vector<Slot> slots_;
  std::unordered_map<uint64_t, PairManifolds> held_;  // by (lower, higher) BodyId
  std::vector<BodyPair> batch_pairs_;
  std::vector<std::pair<btCollisionObject*, btCollisionObject*>> batch_objects_;
  StepResult result_;
  Batch batch_;
  double step_seconds_ = 0;  // the world's time step, from the dispatcher info
  // Scratch kept across pairs and steps, so a steady step allocates nothing.
  std::vector<Candidate> touching_, gaps_, others_;
  std::vector<size_t> chosen_touching_, chosen_gaps_;
  std::vector<double> spread_;
  std::vector<btManifoldPoint> previous_;
};

}  // namespace rtcd::sim
