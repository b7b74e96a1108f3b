// The simulation host: a Bullet world whose collision step is rtcd's batch
// dispatcher, stages assembled from the scene's effects.
#include "rtcd/sim/simulation.hpp"

#include <cmath>
#include <cstring>
#include <limits>
#include <random>
#include <unordered_map>

#include <btBulletDynamicsCommon.h>
#include <BulletCollision/Gimpact/btGImpactCollisionAlgorithm.h>
#include <BulletCollision/Gimpact/btGImpactShape.h>

#include "bullet_math.hpp"
#include "rtcd/backend.hpp"
#include "rtcd/limits.hpp"
#include "rtcd/mesh_check.hpp"
#include "rtcd/mesh_gen.hpp"
#include "rtcd/sim/dispatcher.hpp"
#include "rtcd/sim/mass.hpp"

namespace rtcd::sim {
namespace {

// A dispatcher for scenes without `contacts`: the broad phase still runs,
// nothing answers its pairs.
class NoContacts final : public btCollisionDispatcher {
 public:
  using btCollisionDispatcher::btCollisionDispatcher;
  void dispatchAllCollisionPairs(btOverlappingPairCache*, const btDispatcherInfo&, btDispatcher*) override {}
};

// Bullet's own narrow phase (kGimpact), counted as BatchDispatcher counts
// rtcd's: the batches, and the points Bullet wrote with friction and with
// restitution (it combines them from the bodies' coefficients).
class GimpactDispatcher final : public btCollisionDispatcher {
 public:
  using btCollisionDispatcher::btCollisionDispatcher;
  uint64_t batches = 0;
  size_t friction_points = 0, restitution_points = 0;  // the last batch's

  void dispatchAllCollisionPairs(btOverlappingPairCache* pairs, const btDispatcherInfo& info,
                                 btDispatcher* dispatcher) override {
    btCollisionDispatcher::dispatchAllCollisionPairs(pairs, info, dispatcher);
    ++batches;
    friction_points = restitution_points = 0;
    for (int i = 0; i < getNumManifolds(); ++i) {
      const btPersistentManifold* m = getManifoldByIndexInternal(i);
      for (int k = 0; k < m->getNumContacts(); ++k) {
        const btManifoldPoint& p = m->getContactPoint(k);
        friction_points += p.m_combinedFriction > 0;
        restitution_points += p.m_combinedRestitution > 0 && p.getDistance() < 0;
      }
    }
  }
};

// Bullet's world with its collision and solver phases timed apart.
class TimedWorld final : public btDiscreteDynamicsWorld {
 public:
  using btDiscreteDynamicsWorld::btDiscreteDynamicsWorld;
  double broad = 0, narrow = 0, solver = 0;

  void performDiscreteCollisionDetection() override {
    auto t = Clock::now();
    updateAabbs();
    computeOverlappingPairs();
    broad += seconds_since(t);
    t = Clock::now();
    getDispatcher()->dispatchAllCollisionPairs(m_broadphasePairCache->getOverlappingPairCache(), getDispatchInfo(),
                                               m_dispatcher1);
    narrow += seconds_since(t);
  }

 protected:
  void solveConstraints(btContactSolverInfo& info) override {
    auto t = Clock::now();
    btDiscreteDynamicsWorld::solveConstraints(info);
    solver += seconds_since(t);
  }
};

// Everything bodies of one spec share.
struct Kind {
  std::shared_ptr<const Shape> shape;
  ShapeId id = 0, probe_id = 0;
  MassProperties mass;                  // dynamic kinds only
  Pose principal;                       // principal frame in the shape frame (identity when static)
  double thickness = 0;                 // the thinnest extent of its bounds in the principal frame
  std::unique_ptr<btBoxShape> bounds;   // the broad phase's box, in the principal frame
  std::unique_ptr<btCompoundShape> collision;
  // Bullet's own narrow phase (kGimpact): the mesh in the principal frame,
  // or a primitive placed in it.
  std::vector<btScalar> gimpact_vertices;
  std::vector<int> gimpact_indices;
  std::unique_ptr<btTriangleIndexVertexArray> gimpact_mesh;
  std::unique_ptr<btCollisionShape> gimpact_shape, gimpact_child;
  RenderMesh render;

  btCollisionShape* collision_shape() const { return gimpact_shape ? gimpact_shape.get() : collision.get(); }
};

struct Body {
  std::unique_ptr<btRigidBody> rigid;
  BodyId id = 0;
  size_t spec = 0;  // index into scene.bodies, or SIZE_MAX for the ground
  std::string label;
};

// Uniform in [0, 1) from 53 random bits: the same on every platform.
double unit(std::mt19937_64& rng) { return double(rng() >> 11) * 0x1.0p-53; }

Eigen::Quaterniond random_orientation(std::mt19937_64& rng) {
  // Shoemake's uniform rotation from three uniforms.
  const double u1 = unit(rng), u2 = 2 * M_PI * unit(rng), u3 = 2 * M_PI * unit(rng);
  const double a = std::sqrt(1 - u1), b = std::sqrt(u1);
  return Eigen::Quaterniond(b * std::cos(u3), a * std::sin(u2), a * std::cos(u2), b * std::sin(u3)).normalized();
}

// Bullet's own shape for a kind, in its principal frame.
void make_gimpact_shape(Kind& k) {
  const Pose to_principal = k.principal.inverse();
  if (const Mesh* m = k.shape->mesh()) {
    for (const auto& p : m->positions()) {
      const Eigen::Vector3d q = to_principal.apply(p.cast<double>());
      k.gimpact_vertices.insert(k.gimpact_vertices.end(), {btScalar(q.x()), btScalar(q.y()), btScalar(q.z())});
    }
    for (const auto& t : m->triangles()) k.gimpact_indices.insert(k.gimpact_indices.end(), {int(t[0]), int(t[1]), int(t[2])});
    k.gimpact_mesh = std::make_unique<btTriangleIndexVertexArray>(
        int(m->triangle_count()), k.gimpact_indices.data(), int(3 * sizeof(int)), int(m->vertex_count()),
        k.gimpact_vertices.data(), int(3 * sizeof(btScalar)));
    auto shape = std::make_unique<btGImpactMeshShape>(k.gimpact_mesh.get());
    shape->updateBound();
    k.gimpact_shape = std::move(shape);
    return;
  }
  if (const Sphere* sphere = std::get_if<Sphere>(&k.shape->geometry()))
    k.gimpact_child = std::make_unique<btSphereShape>(btScalar(sphere->radius));
  else
    k.gimpact_child = std::make_unique<btBoxShape>(bt(std::get<Box>(k.shape->geometry()).half_extents));
  auto compound = std::make_unique<btCompoundShape>(false);
  compound->addChildShape(bt(to_principal), k.gimpact_child.get());
  k.gimpact_shape = std::move(compound);
}

// The shape's bounds seen from its principal frame.
Aabb principal_bounds(const Shape& shape, const Pose& principal) {
  Aabb local;
  const Pose to_principal = principal.inverse();
  if (const Mesh* m = shape.mesh()) {
    for (const auto& p : m->positions()) local.extend(to_principal.apply(p.cast<double>()));
    return local;
  }
  const Aabb& b = shape.bounds();
  for (int c = 0; c < 8; ++c)
    local.extend(to_principal.apply({c & 1 ? b.max.x() : b.min.x(), c & 2 ? b.max.y() : b.min.y(),
                                     c & 4 ? b.max.z() : b.min.z()}));
  return local;
}

// The broad phase's shape for a kind: a box around `local`, in the principal frame.
void make_broad_phase_box(Kind& k, const Aabb& local) {
  k.bounds = std::make_unique<btBoxShape>(bt(0.5 * (local.max - local.min)));
  k.collision = std::make_unique<btCompoundShape>(false);
  k.collision->addChildShape(btTransform(btQuaternion::getIdentity(), bt(0.5 * (local.max + local.min))), k.bounds.get());
}

}  // namespace

std::vector<std::shared_ptr<const Shape>> make_shapes(const Scene& scene, std::vector<std::string>* warnings) {
  std::vector<std::shared_ptr<const Shape>> out;
  for (const BodySpec& spec : scene.bodies) {
    if (!spec.mesh.empty()) {
      MeshData data = read_mesh_file(spec.mesh);
      for (auto& p : data.positions) p *= float(spec.scale);
      MeshOptions options;
      options.weld = spec.weld;
      Mesh mesh(std::move(data.positions), std::move(data.triangles), options);
      if (std::string w = self_intersection_warning(mesh, spec.mesh); !w.empty() && warnings) warnings->push_back(w);
      out.push_back(std::make_shared<Shape>(std::move(mesh)));
    } else if (spec.blob) {
      out.push_back(std::make_shared<Shape>(gen::concave_blob(int(spec.blob->triangles), spec.blob->seed, spec.blob->radius)));
    } else if (spec.sphere) {
      out.push_back(std::make_shared<Shape>(Sphere{*spec.sphere}));
    } else {
      out.push_back(std::make_shared<Shape>(Box{*spec.box}));
    }
  }
  return out;
}

struct Simulation::Impl {
  Scene scene;
  std::string backend_name;
  std::unique_ptr<NarrowPhase> narrow;  // the simulation's (contacts only)
  // The interpenetration pass's, stateless, full tracing: the thesis' ray
  // contacts (probe), and the same contacts measured to the nearest surface
  // (truth: the true penetration). Shapes and bodies take the same ids in both.
  std::unique_ptr<NarrowPhase> probe, truth;
  // Pairs the truth pass found deeper than 2% of the smaller body's size,
  // and for how many passes in a row (pair_key -> passes).
  std::unordered_map<uint64_t, uint32_t> deep_runs, deep_runs_next;
  std::unique_ptr<btDefaultCollisionConfiguration> configuration;
  std::unique_ptr<btCollisionDispatcher> dispatcher;
  BatchDispatcher* batch = nullptr;        // dispatcher, when rtcd answers the contacts
  GimpactDispatcher* gimpact = nullptr;    // dispatcher, when Bullet's GIMPACT answers them
  std::unique_ptr<btDbvtBroadphase> broadphase;
  std::unique_ptr<btSequentialImpulseConstraintSolver> solver;
  std::unique_ptr<TimedWorld> world;
  std::vector<Kind> kinds;
  std::unique_ptr<btStaticPlaneShape> ground_plane;
  std::shared_ptr<const Shape> ground_shape;
  std::vector<Body> bodies;
  std::vector<uint32_t> emitted;  // per spec, bodies emitted so far
  std::mt19937_64 rng;
  StageCounters counters;
  StepRecord record;
  std::vector<std::string> warnings;

  Impl(const Scene& s, const std::string& backend_override, int threads);
  ~Impl();
  // Setup, in this order: the narrow phases, Bullet's world, the kinds, the bodies.
  void make_narrow_phases(const std::string& requested, bool use_gimpact, int threads);
  void make_dispatcher(bool use_gimpact);
  void make_world();
  void make_kinds();
  void add_body(size_t spec, const Pose& shape_pose, const Eigen::Vector3d& velocity, const Eigen::Vector3d& spin,
                const std::string& label);
  void add_ground();
  void spawn_initial();
  void emit(double time);
  BodyId register_shape_body(ShapeId id, ShapeId probe_id, const Pose& pose);
  // A body's coefficients as Bullet holds them: GIMPACT combines them into
  // its points, so an effect that is not listed must leave them at zero.
  btScalar bullet_friction(double f) const { return scene.has(Effect::friction) ? btScalar(f) : btScalar(0); }
  btScalar bullet_restitution(double e) const { return scene.has(Effect::restitution) ? btScalar(e) : btScalar(0); }
  // A step's stages around Bullet's, and what it counts after it.
  void apply_gravity();
  void check_poses(uint64_t step) const;
  void count_batch(StepRecord& r);
  void count_gimpact_batch(StepRecord& r);
  double kinetic_energy() const;
  // The interpenetration pass, and its parts.
  void measure();
  std::vector<BodyPair> overlapping_pairs() const;
  void pose_probes();
  void track_deep_pairs(const StepResult& truth_step);
  uint32_t body_number(BodyId id) const;
};

Simulation::Impl::Impl(const Scene& s, const std::string& backend_override, int threads) : scene(s), rng(s.seed) {
  const std::string requested = backend_override.empty() ? scene.backend : backend_override;
  const bool use_gimpact = requested == kGimpact;
  make_narrow_phases(requested, use_gimpact, threads);
  configuration = std::make_unique<btDefaultCollisionConfiguration>();
  make_dispatcher(use_gimpact);
  make_world();
  make_kinds();
  if (scene.ground.present) add_ground();
  emitted.assign(scene.bodies.size(), 0);
  spawn_initial();
}

void Simulation::Impl::make_narrow_phases(const std::string& requested, bool use_gimpact, int threads) {
  const bool contacts = scene.has(Effect::contacts);
  BackendOptions backend = use_gimpact ? BackendOptions{} : BackendOptions::parse(requested);
  if (threads > 0) backend.threads = threads;
  if (contacts && !use_gimpact) narrow = make_narrow_phase(backend, scene.narrow);
  if (scene.has(Effect::interpenetration)) {
    Config c = scene.narrow;
    c.mode = Mode::full;
    c.predictive = false;
    c.nearest_surface = false;
    probe = make_narrow_phase(backend, c);
    c.nearest_surface = true;
    truth = make_narrow_phase(backend, c);
  }
  if (use_gimpact && contacts) backend_name = kGimpact;
  else if (narrow) backend_name = narrow->name();
  else if (probe) backend_name = probe->name();
  else backend_name = "none";
}

// Who answers the broad phase's pairs: Bullet's GIMPACT, rtcd, or no one.
void Simulation::Impl::make_dispatcher(bool use_gimpact) {
  if (use_gimpact) {
    auto d = std::make_unique<GimpactDispatcher>(configuration.get());
    btGImpactCollisionAlgorithm::registerAlgorithm(d.get());
    gimpact = d.get();
    dispatcher = std::move(d);
  } else if (scene.has(Effect::contacts)) {
    DispatcherOptions options;
    options.points_per_pair = scene.points_per_pair;
    options.speculative = scene.has(Effect::speculative);
    options.friction = scene.has(Effect::friction);
    options.restitution = scene.has(Effect::restitution);
    auto d = std::make_unique<BatchDispatcher>(configuration.get(), *narrow, options);
    batch = d.get();
    dispatcher = std::move(d);
  } else {
    dispatcher = std::make_unique<NoContacts>(configuration.get());
  }
}

void Simulation::Impl::make_world() {
  broadphase = std::make_unique<btDbvtBroadphase>();
  solver = std::make_unique<btSequentialImpulseConstraintSolver>();
  world = std::make_unique<TimedWorld>(dispatcher.get(), broadphase.get(), solver.get(), configuration.get());
  world->setGravity(btVector3(0, 0, 0));  // the gravity stage applies it, when listed
  world->getSolverInfo().m_numIterations = int(scene.solver_iterations);
  // Bullet corrects penetrations shallower than this threshold (default
  // -0.04) by adding velocity (Baumgarte), which adds energy: a sphere with
  // restitution 0.8 left the ground at 4.41 m/s after hitting it at 4.43 m/s.
  // At 0 every correction is split from the velocity, so bounces and rest
  // keep their energy.
  world->getSolverInfo().m_splitImpulse = true;
  world->getSolverInfo().m_splitImpulsePenetrationThreshold = 0;
  world->getSolverInfo().m_erp2 = btScalar(scene.solver_erp2);
}

Simulation::Impl::~Impl() {
  for (Body& b : bodies) {
    if (batch) batch->unlink(b.rigid.get());
    world->removeRigidBody(b.rigid.get());
  }
}

void Simulation::Impl::make_kinds() {
  const auto shapes = make_shapes(scene, &warnings);
  for (size_t i = 0; i < scene.bodies.size(); ++i) {
    const BodySpec& spec = scene.bodies[i];
    Kind k;
    k.shape = shapes[i];
    // Two bodies within the extension overlap; a derived one is at least
    // the smaller body's resting extension, which the smaller box's growth covers.
    const double grow = 0.5 * scene.narrow.distance_extension.value_or(resting_extension(k.shape->radius()));
    k.render = look_of(*k.shape);
    if (!spec.is_static) {
      k.mass = spec.mass ? mass_properties_for_mass(*k.shape, *spec.mass) : mass_properties(*k.shape, *spec.density);
      k.principal = k.mass.principal_frame();
    }
    const Aabb local = principal_bounds(*k.shape, k.principal);
    k.thickness = (local.max - local.min).minCoeff();
    make_broad_phase_box(k, local.grown(grow));
    if (gimpact) make_gimpact_shape(k);
    if (narrow) k.id = narrow->add_shape(k.shape);
    if (probe) k.probe_id = probe->add_shape(k.shape);
    if (truth && truth->add_shape(k.shape) != k.probe_id) throw std::logic_error("probe shape ids out of step");
    kinds.push_back(std::move(k));
  }
}

BodyId Simulation::Impl::register_shape_body(ShapeId id, ShapeId probe_id, const Pose& pose) {
  BodyId body = BodyId(bodies.size());
  if (narrow && narrow->add_body(id, pose) != body) throw std::logic_error("narrow-phase body ids out of step");
  if (probe && probe->add_body(probe_id, pose) != body) throw std::logic_error("probe body ids out of step");
  if (truth && truth->add_body(probe_id, pose) != body) throw std::logic_error("probe body ids out of step");
  return body;
}

void Simulation::Impl::add_ground() {
  const Ground& g = scene.ground;
  ground_shape = std::make_shared<Shape>(HalfSpace{});
  Pose pose;
  pose.orientation = Eigen::Quaterniond::FromTwoVectors(Eigen::Vector3d::UnitZ(), g.normal);
  pose.position = g.normal * g.height;
  const ShapeId id = narrow ? narrow->add_shape(ground_shape) : 0;
  const ShapeId probe_id = probe ? probe->add_shape(ground_shape) : 0;
  if (truth && truth->add_shape(ground_shape) != probe_id) throw std::logic_error("probe shape ids out of step");
  ground_plane = std::make_unique<btStaticPlaneShape>(btVector3(0, 0, 1), btScalar(0));
  btRigidBody::btRigidBodyConstructionInfo info(0, nullptr, ground_plane.get());
  info.m_startWorldTransform = bt(pose);
  info.m_friction = bullet_friction(g.friction);
  info.m_restitution = bullet_restitution(g.restitution);
  Body b;
  b.rigid = std::make_unique<btRigidBody>(info);
  b.id = register_shape_body(id, probe_id, pose);
  b.rigid->setUserIndex(int(b.id));  // the interpenetration pass reads ids back from the broad phase
  b.spec = SIZE_MAX;
  b.label = "ground";
  world->addRigidBody(b.rigid.get());
  if (batch) batch->link(b.rigid.get(), {b.id, Pose{}, g.friction, g.restitution});
  bodies.push_back(std::move(b));
}

void Simulation::Impl::add_body(size_t spec_index, const Pose& shape_pose, const Eigen::Vector3d& velocity,
                                const Eigen::Vector3d& spin, const std::string& label) {
  const BodySpec& spec = scene.bodies[spec_index];
  Kind& k = kinds[spec_index];
  const double mass = spec.is_static ? 0.0 : k.mass.mass;
  btRigidBody::btRigidBodyConstructionInfo info(btScalar(mass), nullptr, k.collision_shape(),
                                                spec.is_static ? btVector3(0, 0, 0) : bt(k.mass.principal_moments));
  info.m_startWorldTransform = bt(shape_pose * k.principal);
  info.m_friction = bullet_friction(spec.friction);
  info.m_restitution = bullet_restitution(spec.restitution);
  Body b;
  b.rigid = std::make_unique<btRigidBody>(info);
  b.id = register_shape_body(k.id, k.probe_id, shape_pose);
  b.rigid->setUserIndex(int(b.id));
  b.spec = spec_index;
  b.label = label;
  if (!spec.is_static) {
    b.rigid->setLinearVelocity(bt(velocity));
    b.rigid->setAngularVelocity(bt(spin));
    if (!scene.sleeping) b.rigid->setActivationState(DISABLE_DEACTIVATION);
  }
  world->addRigidBody(b.rigid.get());
  if (batch) batch->link(b.rigid.get(), {b.id, k.principal.inverse(), spec.friction, spec.restitution, k.thickness});
  bodies.push_back(std::move(b));
}

void Simulation::Impl::spawn_initial() {
  for (size_t i = 0; i < scene.bodies.size(); ++i) {
    const BodySpec& spec = scene.bodies[i];
    if (spec.emitter) continue;
    const std::string base = spec.label + (spec.count > 1 ? "#" : "");
    for (uint32_t n = 0; n < spec.count; ++n) {
      Pose pose = spec.pose;
      if (spec.grid) {
        const auto& g = *spec.grid;
        const uint32_t ix = n % g.cells[0], iy = (n / g.cells[0]) % g.cells[1], iz = n / (g.cells[0] * g.cells[1]);
        pose.position = g.origin + g.spacing.cwiseProduct(Eigen::Vector3d(ix, iy, iz));
        for (int a = 0; a < 3; ++a) pose.position[a] += g.jitter * (2 * unit(rng) - 1);
        if (g.random_orientation) pose.orientation = random_orientation(rng);
      }
      add_body(i, pose, spec.velocity, spec.angular_velocity, spec.count > 1 ? base + std::to_string(n) : spec.label);
    }
  }
}

void Simulation::Impl::emit(double time) {
  for (size_t i = 0; i < scene.bodies.size(); ++i) {
    const BodySpec& spec = scene.bodies[i];
    if (!spec.emitter) continue;
    const auto& e = *spec.emitter;
    // Body n appears at time start + n / rate.
    while (emitted[i] < spec.count && e.start + double(emitted[i]) / e.rate <= time + 1e-9) {
      const double at = e.start + double(emitted[i]) / e.rate, angle = e.angular_speed * at;
      Pose pose;
      pose.position = e.centre + e.radius * Eigen::Vector3d(std::cos(angle), std::sin(angle), 0.0);
      if (e.random_orientation) pose.orientation = random_orientation(rng);
      add_body(i, pose, spec.velocity, spec.angular_velocity, spec.label + "#" + std::to_string(emitted[i]));
      ++emitted[i];
    }
  }
}

void Simulation::Impl::measure() {
  const std::vector<BodyPair> pairs = overlapping_pairs();
  pose_probes();
  const StepResult r = probe->detect(pairs);
  double sum = 0, projected = 0, deepest = 0;
  for (const Contact& c : r.contacts) {
    sum += c.depth;
    projected += c.projected_depth;
    deepest = std::max(deepest, c.projected_depth);
  }
  record.interpenetration = sum;
  record.projected = projected;
  record.deepest = deepest;
  sum = deepest = 0;
  const StepResult& t = truth->detect(pairs);
  for (const Contact& c : t.contacts) {
    sum += c.depth;
    deepest = std::max(deepest, c.depth);
  }
  record.true_penetration = sum;
  record.deepest_true = deepest;
  track_deep_pairs(t);
  record.interpenetration_pairs = pairs.size();
  ++counters.interpenetration_passes;
}

// Every pair whose boxes overlap, for the probes to trace in full.
std::vector<BodyPair> Simulation::Impl::overlapping_pairs() const {
  std::vector<BodyPair> pairs;
  btOverlappingPairCache* cache = world->getBroadphase()->getOverlappingPairCache();
  btBroadphasePairArray& array = cache->getOverlappingPairArray();
  for (int i = 0; i < cache->getNumOverlappingPairs(); ++i) {
    auto* o0 = static_cast<btRigidBody*>(array[i].m_pProxy0->m_clientObject);
    auto* o1 = static_cast<btRigidBody*>(array[i].m_pProxy1->m_clientObject);
    if (o0->isStaticObject() && o1->isStaticObject()) continue;
    pairs.push_back({BodyId(o0->getUserIndex()), BodyId(o1->getUserIndex())});
  }
  return pairs;
}

// The probes' bodies where Bullet's are, in their shape frames.
void Simulation::Impl::pose_probes() {
  for (const Body& b : bodies) {
    const Kind* k = b.spec == SIZE_MAX ? nullptr : &kinds[b.spec];
    const Pose pose = pose_of(b.rigid->getWorldTransform()) * (k ? k->principal.inverse() : Pose{});
    probe->set_pose(b.id, pose);
    truth->set_pose(b.id, pose);
  }
}

// Pairs held deep: deeper than 2% of a pair's size, its smaller body's
// diameter (the ground has none), and for how many passes in a row; and
// the deepest body in the ground, over its size.
void Simulation::Impl::track_deep_pairs(const StepResult& truth_step) {
  const auto size = [&](BodyId id) {
    const Body& b = bodies[id];
    return b.spec == SIZE_MAX ? INFINITY : 2.0 * kinds[b.spec].shape->radius();
  };
  deep_runs_next.clear();
  uint32_t longest = 0;
  BodyPair held{};
  record.ground_depth_fraction = 0;
  for (const PairResult& p : truth_step.pairs) {
    const double smaller = std::min(size(p.pair.a), size(p.pair.b)), larger = std::max(size(p.pair.a), size(p.pair.b));
    if (std::isinf(larger) && p.max_depth > 0)
      record.ground_depth_fraction = std::max(record.ground_depth_fraction, p.max_depth / smaller);
    if (!(p.max_depth > 0.02 * std::min(size(p.pair.a), size(p.pair.b)))) continue;
    const uint64_t key = pair_key(p.pair.a, p.pair.b);
    const auto before = deep_runs.find(key);
    const uint32_t run = (before == deep_runs.end() ? 0 : before->second) + 1;
    deep_runs_next[key] = run;
    if (run > longest) longest = run, held = p.pair;
  }
  deep_runs.swap(deep_runs_next);
  record.deep_pairs = deep_runs.size();
  record.longest_deep_run = uint64_t(longest) * scene.interpenetration_every;
  record.longest_deep_pair = longest ? BodyPair{body_number(held.a), body_number(held.b)} : BodyPair{};
}

// A body named as bodies() numbers them (the ground not counted).
uint32_t Simulation::Impl::body_number(BodyId id) const {
  if (bodies[id].spec == SIZE_MAX) return Simulation::kGround;
  uint32_t n = 0;
  for (BodyId k = 0; k < id; ++k) n += bodies[k].spec != SIZE_MAX;
  return n;
}

Simulation::Simulation(const Scene& scene, const std::string& backend, int threads)
    : impl_(std::make_unique<Impl>(scene, backend, threads)) {}

Simulation::~Simulation() = default;

void Simulation::Impl::apply_gravity() {
  const btVector3 g = bt(scene.gravity);
  for (Body& b : bodies) {
    if (b.rigid->isStaticObject()) continue;
    b.rigid->applyCentralForce(g / b.rigid->getInvMass());
    ++counters.gravity_forces;
  }
}

// A body that blew up stops the run, named.
void Simulation::Impl::check_poses(uint64_t step) const {
  for (const Body& b : bodies) {
    const btTransform& x = b.rigid->getWorldTransform();
    const btVector3& o = x.getOrigin();
    const btQuaternion q = x.getRotation();
    if (!std::isfinite(o.x() + o.y() + o.z() + q.x() + q.y() + q.z() + q.w()))
      throw SimulationError("step " + std::to_string(step) + ": body " + b.label + " has a non-finite pose");
  }
}

// What rtcd's narrow phase did in the step.
void Simulation::Impl::count_batch(StepRecord& r) {
  const auto& last = batch->last_batch();
  const StepResult& n = batch->last_step();
  counters.narrow_phase_batches = last.calls;
  counters.friction_points += last.friction_points;
  counters.restitution_points += last.restitution_points;
  counters.speculative_points += last.speculative_points;
  counters.entry_pushes += last.entry_pushes;
  r.pairs = last.pairs;
  r.pairs_full = n.stats.pairs_full;
  r.pairs_iterative = n.stats.pairs_iterative;
  r.rays = n.stats;
  r.devices = n.stats.devices;
  r.cpu_fallback = n.stats.cpu_fallback;
  r.contacts = n.contacts.size();
  r.predictive = n.predictive.size();
  r.solver_points = last.points;
  r.speculative_points = last.speculative_points;
  const BodyId ground = scene.ground.present ? 0 : UINT32_MAX;  // the ground is made first
  for (const Contact& c : n.contacts) r.ground_contacts += c.source_body == ground || c.target_body == ground;
}

// What Bullet's GIMPACT did in the step, counted from its manifolds.
void Simulation::Impl::count_gimpact_batch(StepRecord& r) {
  counters.narrow_phase_batches = gimpact->batches;
  counters.friction_points += gimpact->friction_points;
  counters.restitution_points += gimpact->restitution_points;
  r.pairs = size_t(world->getBroadphase()->getOverlappingPairCache()->getNumOverlappingPairs());
  btDispatcher* d = dispatcher.get();
  const btCollisionObject* ground = scene.ground.present ? bodies[0].rigid.get() : nullptr;
  for (int i = 0; i < d->getNumManifolds(); ++i) {
    const btPersistentManifold* manifold = d->getManifoldByIndexInternal(i);
    const size_t points = size_t(manifold->getNumContacts());
    r.contacts += points;
    r.solver_points += points;
    r.ground_contacts += manifold->getBody0() == ground || manifold->getBody1() == ground ? points : 0;
  }
}

double Simulation::Impl::kinetic_energy() const {
  double energy = 0;
  for (const Body& b : bodies) {
    if (b.rigid->isStaticObject()) continue;
    const Kind& k = kinds[b.spec];
    const Eigen::Vector3d v = eigen(b.rigid->getLinearVelocity());
    const Eigen::Vector3d w_body = eigen(quatRotate(b.rigid->getOrientation().inverse(), b.rigid->getAngularVelocity()));
    energy += 0.5 * k.mass.mass * v.squaredNorm() + 0.5 * w_body.dot(k.mass.principal_moments.cwiseProduct(w_body));
  }
  return energy;
}

const StepRecord& Simulation::step() {
  Impl& m = *impl_;
  const auto t0 = Clock::now();
  const uint64_t index = m.counters.steps;
  StepRecord& r = m.record;
  r = {};
  r.step = index;
  r.time = double(index + 1) * m.scene.time_step;

  double effects = 0;
  auto t = Clock::now();
  m.emit(double(index) * m.scene.time_step);
  if (m.scene.has(Effect::gravity)) m.apply_gravity();
  effects += seconds_since(t);

  m.world->broad = m.world->narrow = m.world->solver = 0;
  // One variable step of the scene's length (below kMinTimeStep Bullet
  // would take none), or that many fixed sub-steps of it.
  static_assert(kMinTimeStep > SIMD_EPSILON);
  const uint32_t substeps = m.scene.solver_substeps;
  if (substeps == 1) m.world->stepSimulation(btScalar(m.scene.time_step), 0, btScalar(m.scene.time_step));
  else m.world->stepSimulation(btScalar(m.scene.time_step), int(substeps), btScalar(m.scene.time_step / substeps));
  m.check_poses(index);
  ++m.counters.steps;

  r.bodies = m.bodies.size();
  r.seconds_broad = m.world->broad;
  r.seconds_narrow = m.world->narrow;
  r.seconds_solver = m.world->solver;
  if (m.batch) m.count_batch(r);
  else if (m.gimpact) m.count_gimpact_batch(r);
  r.kinetic_energy = m.kinetic_energy();

  t = Clock::now();
  const bool last_step = m.counters.steps == m.scene.steps;
  if (m.probe && ((index + 1) % m.scene.interpenetration_every == 0 || last_step)) m.measure();
  effects += seconds_since(t);
  r.seconds_effects = effects;
  r.seconds_total = seconds_since(t0);
  return r;
}

const StepRecord& Simulation::last() const { return impl_->record; }
uint64_t Simulation::steps_done() const { return impl_->counters.steps; }
const Scene& Simulation::scene() const { return impl_->scene; }
const StageCounters& Simulation::counters() const { return impl_->counters; }
std::string Simulation::backend() const { return impl_->backend_name; }
const std::vector<std::string>& Simulation::warnings() const { return impl_->warnings; }

std::vector<std::string> Simulation::devices() const {
  if (impl_->narrow) return impl_->narrow->devices();
  if (impl_->probe) return impl_->probe->devices();
  return {};
}

std::span<const BodyPair> Simulation::last_pairs() const {
  if (!impl_->batch) return {};
  return impl_->batch->last_pairs();
}

std::vector<uint32_t> Simulation::body_kinds() const {
  std::vector<uint32_t> out;
  for (const Body& b : impl_->bodies) out.push_back(b.spec == SIZE_MAX ? kGroundKind : uint32_t(b.spec));
  return out;
}

void Simulation::shape_poses(std::vector<Pose>& out) const {
  out.clear();
  for (const Body& b : impl_->bodies) {
    const Pose world = pose_of(b.rigid->getWorldTransform());
    out.push_back(b.spec == SIZE_MAX ? world : world * impl_->kinds[b.spec].principal.inverse());
  }
}

const StepResult& Simulation::last_narrow_phase() const {
  static const StepResult none;
  return impl_->batch ? impl_->batch->last_step() : none;
}

namespace {
// Each narrow-phase BodyId's place in bodies() (kGround for the ground).
std::vector<uint32_t> body_numbers(const std::vector<uint32_t>& kinds) {
  std::vector<uint32_t> out;
  uint32_t next = 0;
  for (uint32_t kind : kinds) out.push_back(kind == Simulation::kGroundKind ? Simulation::kGround : next++);
  return out;
}
}  // namespace

StepResult Simulation::contacts() const {
  StepResult r = last_narrow_phase();
  const std::vector<uint32_t> number = body_numbers(body_kinds());
  for (Contact& c : r.contacts) c.source_body = number[c.source_body], c.target_body = number[c.target_body];
  for (PredictiveRay& p : r.predictive) p.source_body = number[p.source_body], p.target_body = number[p.target_body];
  for (PairResult& p : r.pairs) p.pair = {number[p.pair.a], number[p.pair.b]};
  return r;
}

std::vector<BodyPair> Simulation::pairs() const {
  const std::vector<uint32_t> number = body_numbers(body_kinds());
  std::vector<BodyPair> out;
  for (const BodyPair& p : last_pairs()) out.push_back({number[p.a], number[p.b]});
  return out;
}

std::vector<BodyState> Simulation::bodies() const {
  std::vector<BodyState> out;
  for (const Body& b : impl_->bodies) {
    if (b.spec == SIZE_MAX) continue;
    const Kind& k = impl_->kinds[b.spec];
    BodyState s;
    s.label = b.label;
    s.pose = pose_of(b.rigid->getWorldTransform()) * k.principal.inverse();
    s.linear_velocity = eigen(b.rigid->getLinearVelocity());
    s.angular_velocity = eigen(b.rigid->getAngularVelocity());
    s.is_static = b.rigid->isStaticObject();
    s.mass = s.is_static ? 0.0 : k.mass.mass;
    s.spec = b.spec;
    out.push_back(s);
  }
  return out;
}

uint64_t Simulation::state_hash() const {
  // FNV-1a over the exact bits of every transform and velocity.
  uint64_t h = 1469598103934665603ull;
  const auto mix = [&h](btScalar v) {
    uint32_t bits;
    std::memcpy(&bits, &v, sizeof bits);
    for (int i = 0; i < 4; ++i) {
      h ^= (bits >> (8 * i)) & 0xffu;
      h *= 1099511628211ull;
    }
  };
  for (const Body& b : impl_->bodies) {
    const btTransform& x = b.rigid->getWorldTransform();
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) mix(x.getBasis()[r][c]);
    for (int i = 0; i < 3; ++i) {
      mix(x.getOrigin()[i]);
      mix(b.rigid->getLinearVelocity()[i]);
      mix(b.rigid->getAngularVelocity()[i]);
    }
  }
  return h;
}

void Simulation::measure_interpenetration() {
  if (!impl_->probe) throw UsageError("the scene does not list \"interpenetration\"");
  impl_->measure();
}

Image Simulation::snapshot(int width, int height, bool full_rays) {
  const Impl& m = *impl_;
  ++impl_->counters.snapshots;
  std::vector<RenderMesh> meshes;
  for (const Kind& k : m.kinds) meshes.push_back(k.render);
  std::vector<RenderInstance> instances;
  Aabb box;
  for (const BodyState& s : bodies()) {
    instances.push_back({uint32_t(s.spec), s.pose, s.is_static ? kStaticColour : kind_colour(s.spec)});
    box.extend(s.pose.apply(m.kinds[s.spec].shape->bounds().min));
    box.extend(s.pose.apply(m.kinds[s.spec].shape->bounds().max));
  }
  if (box.empty()) box = {Eigen::Vector3d::Constant(-1), Eigen::Vector3d::Constant(1)};
  if (m.scene.ground.present) {
    // The ground drawn as a square around the bodies, in the plane.
    const double half = 0.75 * (box.max - box.min).norm() + 1.0;
    meshes.push_back(ground_square(Eigen::Vector3d::Zero(), half));
    Pose ground;
    ground.orientation = Eigen::Quaterniond::FromTwoVectors(Eigen::Vector3d::UnitZ(), m.scene.ground.normal);
    const Eigen::Vector3d centre = 0.5 * (box.min + box.max);
    ground.position = centre - m.scene.ground.normal * (m.scene.ground.normal.dot(centre) - m.scene.ground.height);
    instances.push_back({uint32_t(meshes.size() - 1), ground, kGroundColour});
  }
  const std::vector<RenderLine> lines = contact_lines(last_narrow_phase().contacts, full_rays);
  Camera camera = frame_camera(box);
  if (m.scene.camera_eye) camera.eye = *m.scene.camera_eye;
  if (m.scene.camera_target) camera.target = *m.scene.camera_target;
  return sim::render(meshes, instances, lines, camera, width, height);
}

}  // namespace rtcd::sim
