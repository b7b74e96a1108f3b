// Scene files: strict JSON reading, every error naming its key path.
#include "rtcd/sim/scene.hpp"

#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>

#include <nlohmann/json.hpp>

#include "rtcd/mesh.hpp"

namespace rtcd::sim {
namespace {

using Json = nlohmann::json;

constexpr std::pair<Effect, const char*> kEffects[] = {
    {Effect::gravity, "gravity"},         {Effect::contacts, "contacts"},
    {Effect::friction, "friction"},       {Effect::restitution, "restitution"},
    {Effect::predictive, "predictive"},   {Effect::speculative, "speculative"},
    {Effect::projected, "projected"},     {Effect::interpenetration, "interpenetration"},
    {Effect::snapshots, "snapshots"},
};

// An effect and the one it cannot run without.
constexpr std::pair<Effect, Effect> kNeeds[] = {
    {Effect::friction, Effect::contacts},    {Effect::restitution, Effect::contacts},
    {Effect::predictive, Effect::contacts},  {Effect::projected, Effect::contacts},
    {Effect::speculative, Effect::predictive},
};

// One JSON object being read: every key read is checked off, and a key
// nobody read is an error naming it.
class Object {
 public:
  Object(const Json& json, std::string path, const std::string& file) : json_(json), path_(std::move(path)), file_(file) {
    if (!json_.is_object()) fail(path_, "must be an object");
  }

  [[noreturn]] void fail(const std::string& key_path, const std::string& what) const {
    throw SceneError(file_ + ": " + (key_path.empty() ? std::string("the scene") : key_path) + ": " + what);
  }
  std::string key(const std::string& k) const { return path_.empty() ? k : path_ + "." + k; }
  const std::string& where() const { return path_; }

  const Json* find(const std::string& k) {
    read_.insert(k);
    auto it = json_.find(k);
    return it == json_.end() ? nullptr : &*it;
  }
  bool has(const std::string& k) const { return json_.contains(k); }

  double number(const std::string& k, double fallback, double lo, double hi) {
    const Json* j = find(k);
    if (!j) return fallback;
    if (!j->is_number()) fail(key(k), "must be a number");
    const double v = j->get<double>();
    if (!std::isfinite(v) || v < lo || v > hi) {
      std::ostringstream s;
      s << "is " << v << ", must be in [" << lo << ", " << hi << "]";
      fail(key(k), s.str());
    }
    return v;
  }
  std::optional<double> positive(const std::string& k, double hi = 1e30) {
    if (!has(k)) {
      read_.insert(k);
      return std::nullopt;
    }
    const double v = number(k, 0.0, 0.0, hi);
    if (!(v > 0)) fail(key(k), "must be > 0");
    return v;
  }
  uint64_t integer(const std::string& k, uint64_t fallback, uint64_t lo, uint64_t hi) {
    const Json* j = find(k);
    if (!j) return fallback;
    if (!j->is_number_integer() && !j->is_number_unsigned()) fail(key(k), "must be an integer");
    if (j->is_number_integer() && j->get<int64_t>() < 0) fail(key(k), "must not be negative");
    const uint64_t v = j->get<uint64_t>();
    if (v < lo || v > hi) fail(key(k), "is " + std::to_string(v) + ", must be in [" + std::to_string(lo) + ", " + std::to_string(hi) + "]");
    return v;
  }
  bool boolean(const std::string& k, bool fallback) {
    const Json* j = find(k);
    if (!j) return fallback;
    if (!j->is_boolean()) fail(key(k), "must be true or false");
    return j->get<bool>();
  }
  std::string string(const std::string& k, const std::string& fallback) {
    const Json* j = find(k);
    if (!j) return fallback;
    if (!j->is_string()) fail(key(k), "must be a string");
    return j->get<std::string>();
  }
  Eigen::Vector3d vector(const std::string& k, const Eigen::Vector3d& fallback, double bound = 1e9) {
    const Json* j = find(k);
    if (!j) return fallback;
    if (!j->is_array() || j->size() != 3) fail(key(k), "must be an array of 3 numbers");
    Eigen::Vector3d v;
    for (int i = 0; i < 3; ++i) {
      if (!(*j)[i].is_number()) fail(key(k), "must be an array of 3 numbers");
      v[i] = (*j)[i].get<double>();
      if (!std::isfinite(v[i]) || std::abs(v[i]) > bound) fail(key(k), "has a component beyond ±" + std::to_string(bound));
    }
    return v;
  }
  Object object(const std::string& k) {
    const Json* j = find(k);
    static const Json empty = Json::object();
    return Object(j ? *j : empty, key(k), file_);
  }

  // Unknown keys are errors, so a typo never silently keeps a default.
  void finish() const {
    for (auto it = json_.begin(); it != json_.end(); ++it)
      if (!read_.contains(it.key())) fail(key(it.key()), "unknown key");
  }

 private:
  const Json& json_;
  std::string path_;
  const std::string& file_;
  std::set<std::string> read_;
};

Pose read_pose(Object o) {
  Pose p;
  p.position = o.vector("position", Eigen::Vector3d::Zero());
  if (const Json* q = o.find("orientation")) {
    if (!q->is_array() || q->size() != 4 || !std::all_of(q->begin(), q->end(), [](const Json& x) { return x.is_number(); }))
      o.fail(o.key("orientation"), "must be a quaternion [w, x, y, z]");
    Eigen::Quaterniond r((*q)[0].get<double>(), (*q)[1].get<double>(), (*q)[2].get<double>(), (*q)[3].get<double>());
    if (!r.coeffs().allFinite() || r.norm() < 1e-6) o.fail(o.key("orientation"), "must be a non-zero quaternion");
    p.orientation = r.normalized();
  }
  o.finish();
  return p;
}

BodySpec read_body(Object o, size_t index, const std::string& folder, const SceneLimits& limits) {
  BodySpec b;
  b.label = o.string("name", "bodies[" + std::to_string(index) + "]");
  int shapes = 0;
  if (o.has("mesh")) {
    ++shapes;
    b.mesh = o.string("mesh", "");
    const std::filesystem::path p(b.mesh);
    const std::string resolved = p.is_absolute() ? b.mesh : (std::filesystem::path(folder) / p).lexically_normal().string();
    const bool exists = limits.file_exists ? limits.file_exists(resolved) : std::filesystem::is_regular_file(resolved);
    if (!exists) o.fail(o.key("mesh"), "no such mesh file: " + resolved);
    b.mesh = resolved;
    b.scale = o.number("scale", 1.0, 1e-6, 1e6);
    b.weld = o.boolean("weld", false);
  }
  if (o.has("blob")) {
    ++shapes;
    Object g = o.object("blob");
    BodySpec::Blob blob;
    blob.triangles = uint32_t(g.integer("triangles", blob.triangles, 8, 2'000'000));
    if (blob.triangles % 2) g.fail(g.key("triangles"), "must be even");
    blob.seed = uint32_t(g.integer("seed", blob.seed, 0, UINT32_MAX));
    blob.radius = g.number("radius", 1.0, 1e-6, 1e6);
    g.finish();
    b.blob = blob;
  }
  if (o.has("sphere")) {
    ++shapes;
    b.sphere = o.positive("sphere", 1e6);
    if (2 * *b.sphere < kMinBodySize)
      o.fail(o.key("sphere"), "is below the smallest body the narrow phase takes (a diagonal of 1e-9)");
  }
  if (o.has("box")) {
    ++shapes;
    b.box = o.vector("box", Eigen::Vector3d::Ones(), 1e6);
    if ((b.box->array() <= 0).any()) o.fail(o.key("box"), "half extents must be > 0");
    if (2 * b.box->norm() < kMinBodySize)
      o.fail(o.key("box"), "is below the smallest body the narrow phase takes (a diagonal of 1e-9)");
  }
  if (shapes != 1) o.fail(o.where(), shapes ? "names more than one shape (mesh, blob, sphere, box)" : "needs a shape: mesh, blob, sphere or box");

  b.count = uint32_t(o.integer("count", 1, 1, limits.max_bodies));
  b.is_static = o.boolean("static", false);
  b.mass = o.positive("mass");
  b.density = o.positive("density");
  if (b.mass && b.density) o.fail(o.key("mass"), "and density are both given; give one");
  if (b.is_static && (b.mass || b.density)) o.fail(o.key("static"), "a static body has no mass or density");
  if (!b.is_static && !b.mass && !b.density) b.density = 1000.0;
  b.friction = o.number("friction", 0.5, 0.0, 10.0);
  b.restitution = o.number("restitution", 0.0, 0.0, 1.0);
  b.velocity = o.vector("velocity", Eigen::Vector3d::Zero(), 1e6);
  b.angular_velocity = o.vector("angular_velocity", Eigen::Vector3d::Zero(), 1e6);

  const int placements = int(o.has("pose")) + int(o.has("grid")) + int(o.has("emitter"));
  if (placements > 1) o.fail(o.key("pose"), "pose, grid and emitter exclude each other");
  if (o.has("pose")) b.pose = read_pose(o.object("pose"));
  if (o.has("grid")) {
    Object g = o.object("grid");
    BodySpec::Grid grid;
    const Json* cells = g.find("cells");
    if (!cells || !cells->is_array() || cells->size() != 3 ||
        !std::all_of(cells->begin(), cells->end(), [](const Json& x) { return x.is_number_unsigned() && x.get<uint64_t>() >= 1 && x.get<uint64_t>() <= 100000; }))
      g.fail(g.key("cells"), "must be an array of 3 integers >= 1");
    for (int i = 0; i < 3; ++i) grid.cells[i] = (*cells)[i].get<uint32_t>();
    grid.origin = g.vector("origin", Eigen::Vector3d::Zero());
    grid.spacing = g.vector("spacing", Eigen::Vector3d::Ones(), 1e6);
    grid.jitter = g.number("jitter", 0.0, 0.0, 1e6);
    grid.random_orientation = g.boolean("random_orientation", false);
    g.finish();
    if (uint64_t(grid.cells[0]) * grid.cells[1] * grid.cells[2] < b.count)
      g.fail(g.key("cells"), "holds fewer cells than count (" + std::to_string(b.count) + ")");
    b.grid = grid;
  } else if (o.has("emitter")) {
    Object e = o.object("emitter");
    BodySpec::Emitter em;
    if (!e.has("rate")) e.fail(e.key("rate"), "is required");
    em.rate = *e.positive("rate", 1e6);
    em.centre = e.vector("centre", Eigen::Vector3d::Zero());
    em.radius = e.number("radius", 0.0, 0.0, 1e6);
    em.angular_speed = e.number("angular_speed", 0.0, -1e3, 1e3);
    em.start = e.number("start", 0.0, 0.0, 1e9);
    em.random_orientation = e.boolean("random_orientation", true);
    e.finish();
    if (b.is_static) e.fail(e.key("rate"), "a static body cannot be emitted");
    b.emitter = em;
  } else if (b.count > 1) {
    o.fail(o.key("count"), "is " + std::to_string(b.count) + ": more than one body needs a grid or an emitter");
  }
  o.finish();
  return b;
}

}  // namespace

const char* to_string(Effect effect) {
  for (const auto& [e, name] : kEffects)
    if (e == effect) return name;
  return "?";
}

std::optional<Effect> parse_effect(std::string_view name) {
  for (const auto& [e, n] : kEffects)
    if (name == n) return e;
  return std::nullopt;
}

uint64_t Scene::body_count() const {
  uint64_t n = 0;
  for (const BodySpec& b : bodies) n += b.count;
  return n;
}

Scene parse_scene(std::string_view json_text, const std::string& path, const SceneLimits& limits) {
  Json json;
  try {
    json = Json::parse(json_text);
  } catch (const Json::exception& e) {  // a syntax error, or a number beyond a double
    throw SceneError(path + ": not valid JSON: " + e.what());
  }
  Object root(json, "", path);
  Scene s;
  s.path = path;
  s.name = root.string("name", std::filesystem::path(path).stem().string());
  s.time_step = root.number("time_step", 1.0 / 60.0, kMinTimeStep, 10.0);
  if (root.has("steps") && root.has("duration")) root.fail("steps", "and duration are both given; give one");
  if (root.has("duration")) {
    const double d = root.number("duration", 0.0, 0.0, 1e9);
    const double n = std::ceil(d / s.time_step - 1e-9);
    if (!(n >= 1) || n > double(limits.max_steps)) root.fail("duration", "gives " + std::to_string(n) + " steps, must give 1 to " + std::to_string(limits.max_steps));
    s.steps = uint64_t(n);
  } else {
    s.steps = root.integer("steps", 60, 1, limits.max_steps);
  }
  s.seed = root.integer("seed", 1, 0, UINT64_MAX);
  s.sleeping = root.boolean("sleeping", false);
  s.gravity = root.vector("gravity", s.gravity, 1e6);

  const Json* effects = root.find("effects");
  if (!effects) root.fail("effects", "is required: list the effects this scene simulates");
  if (!effects->is_array()) root.fail("effects", "must be an array of effect names");
  for (size_t i = 0; i < effects->size(); ++i) {
    const std::string key = "effects[" + std::to_string(i) + "]";
    if (!(*effects)[i].is_string()) root.fail(key, "must be a string");
    const auto e = parse_effect((*effects)[i].get<std::string>());
    if (!e) {
      std::string known;
      for (const auto& [_, n] : kEffects) known += std::string(known.empty() ? "" : ", ") + n;
      root.fail(key, "unknown effect \"" + (*effects)[i].get<std::string>() + "\" (known: " + known + ")");
    }
    if (!s.effects.insert(*e).second) root.fail(key, "\"" + std::string(to_string(*e)) + "\" is listed twice");
  }
  for (const auto& [effect, needed] : kNeeds)
    if (s.has(effect) && !s.has(needed))
      root.fail("effects", std::string("\"") + to_string(effect) + "\" needs \"" + to_string(needed) + "\"");

  Object np = root.object("narrow_phase");
  s.backend = np.string("backend", "auto");
  // The knobs by the table (config.hpp); those the effects list owns are
  // set from it, and a narrow_phase key for them is an error.
  for (const Knob& knob : knobs()) {
    const std::string name = knob.name;
    if (knob.effect) {
      if (np.has(name))
        np.fail(np.key(name), "conflicts with effects: list \"" + name +
                                  "\" in effects (the one place that turns it on) and remove narrow_phase." + name);
      const std::optional<Effect> effect = parse_effect(name);
      knob.set(s.narrow, s.has(*effect));
      continue;
    }
    switch (knob.type) {
      case KnobType::flag:
        knob.set(s.narrow, np.boolean(name, std::get<bool>(knob.get(s.narrow))));
        break;
      case KnobType::count:  // left out: derived per pair (rtcd/limits.hpp)
        if (np.has(name)) knob.set(s.narrow, double(np.integer(name, 0, uint64_t(knob.min), uint64_t(knob.max))));
        break;
      case KnobType::length:
        if (np.has(name)) knob.set(s.narrow, np.number(name, 0.0, knob.min, knob.max));
        break;
      case KnobType::mode: {
        const std::string mode = np.string(name, to_string(s.narrow.mode));
        try {
          knob.set(s.narrow, parse_mode(mode));
        } catch (const Error&) {
          np.fail(np.key(name), "is \"" + mode + "\", must be full, iterative or auto");
        }
        break;
      }
    }
  }
  try {
    s.narrow.validate();  // the rules between knobs
  } catch (const ConfigError& e) {
    np.fail(np.key("displacement_threshold"), e.what());
  }
  s.points_per_pair = uint32_t(np.integer("points_per_pair", s.points_per_pair, 1, 64));
  np.finish();

  Object solver = root.object("solver");
  s.solver_iterations = uint32_t(solver.integer("iterations", s.solver_iterations, 1, 1000));
  s.solver_substeps = uint32_t(solver.integer("substeps", s.solver_substeps, 1, 64));
  s.solver_erp2 = solver.number("erp2", s.solver_erp2, 0.01, 1.0);
  if (s.time_step / s.solver_substeps < kMinTimeStep)
    solver.fail(solver.key("substeps"), "makes sub-steps shorter than " + std::to_string(kMinTimeStep) + " s (time_step / substeps)");
  solver.finish();

  Object ip = root.object("interpenetration");
  s.interpenetration_every = uint32_t(ip.integer("every", s.interpenetration_every, 1, 1'000'000));
  ip.finish();

  Object snap = root.object("snapshots");
  if (const Json* steps = snap.find("steps")) {
    if (!steps->is_array() || steps->empty()) snap.fail(snap.key("steps"), "must be a non-empty array of step numbers");
    s.snapshot_steps.clear();
    for (const Json& v : *steps) {
      if (!v.is_number_integer()) snap.fail(snap.key("steps"), "must hold integers (negative counts from the end)");
      const int64_t k = v.get<int64_t>();
      if (k >= int64_t(s.steps) || k < -int64_t(s.steps))
        snap.fail(snap.key("steps"), "step " + std::to_string(k) + " is outside the run's " + std::to_string(s.steps) + " steps");
      s.snapshot_steps.push_back(k);
    }
  }
  s.snapshot_width = int(snap.integer("width", s.snapshot_width, 16, 8192));
  s.snapshot_height = int(snap.integer("height", s.snapshot_height, 16, 8192));
  if (snap.has("eye")) s.camera_eye = snap.vector("eye", Eigen::Vector3d::Zero());
  if (snap.has("target")) s.camera_target = snap.vector("target", Eigen::Vector3d::Zero());
  snap.finish();

  if (const Json* g = root.find("ground"); g && g->is_boolean() && !g->get<bool>()) {
    s.ground.present = false;
  } else {
    Object ground = root.object("ground");
    s.ground.height = ground.number("height", 0.0, -1e9, 1e9);
    s.ground.normal = ground.vector("normal", Eigen::Vector3d::UnitZ());
    if (s.ground.normal.norm() < 1e-9) ground.fail(ground.key("normal"), "must be a non-zero vector");
    s.ground.normal.normalize();
    s.ground.friction = ground.number("friction", 0.5, 0.0, 10.0);
    s.ground.restitution = ground.number("restitution", 0.0, 0.0, 1.0);
    ground.finish();
  }

  const Json* bodies = root.find("bodies");
  if (!bodies || !bodies->is_array()) root.fail("bodies", "must be an array of bodies");
  const std::string folder = std::filesystem::path(path).parent_path().string();
  for (size_t i = 0; i < bodies->size(); ++i)
    s.bodies.push_back(read_body(Object((*bodies)[i], "bodies[" + std::to_string(i) + "]", path), i, folder, limits));
  root.finish();
  if (s.body_count() > limits.max_bodies)
    root.fail("bodies", std::to_string(s.body_count()) + " bodies, more than " + std::to_string(limits.max_bodies));
  return s;
}

Scene load_scene(const std::string& path, const SceneLimits& limits) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw SceneError(path + ": cannot read the scene file");
  std::stringstream text;
  text << in.rdbuf();
  return parse_scene(text.str(), path, limits);
}

}  // namespace rtcd::sim
