// What every step of the narrow phase must satisfy whatever the input:
// checks shared by the fuzz harnesses. A violation prints what broke and
// aborts, which libFuzzer reports as a crash and saves the input.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <set>
#include <string>
#include <utility>

#include "rtcd/backend.hpp"
#include "rtcd/narrow_phase.hpp"

namespace rtcd::fuzz {

[[noreturn]] inline void violated(const std::string& what) {
  std::fprintf(stderr, "rtcd fuzz: invariant violated: %s\n", what.c_str());
  std::fflush(stderr);
  std::abort();
}

// The usable CPU backends (basic, and embree where built): the harnesses
// pin these, so no input pays for an OpenCL context (fuzz/opencl.cpp keeps
// one for its whole run).
inline std::vector<std::string> cpu_backends() {
  std::vector<std::string> names;
  for (const auto& b : available_backends())
    if (b.usable && (b.name == "basic" || b.name == "embree")) names.push_back(b.name);
  return names;
}

inline std::string num(double v) {
  char text[32];
  std::snprintf(text, sizeof text, "%.9g", v);
  return text;
}

inline void require(bool ok, const std::string& what) {
  if (!ok) violated(what);
}

// Number of faces a ray can report against `target`: triangles, box faces, 1 for a sphere or a half-space.
inline size_t face_count(const Shape& target) {
  if (const Mesh* m = target.mesh()) return m->triangle_count();
  return std::holds_alternative<Box>(target.geometry()) ? 6 : 1;
}

inline bool unit(const Eigen::Vector3d& v) { return v.allFinite() && std::abs(v.norm() - 1.0) <= 1e-3; }

// Checks one step's result for the single pair (a, b) on `backend`.
inline void check_step(const std::string& backend, const StepResult& r, BodyPair pair, const Shape& a,
                       const Shape& b, const Config& config) {
  const std::string where = backend + ": ";
  require(r.pairs.size() == 1, where + "expected one pair result");
  const PairResult& p = r.pairs[0];
  require(p.pair.a == pair.a && p.pair.b == pair.b, where + "pair result names another pair");
  require(p.first_contact + p.contact_count <= r.contacts.size(), where + "contact range out of bounds");
  require(p.first_predictive + p.predictive_count <= r.predictive.size(), where + "predictive range out of bounds");
  require(p.colliding == (p.contact_count > 0), where + "colliding disagrees with the contact count");
  require(config.predictive || r.predictive.empty(), where + "predictive rays with Config::predictive off");

  auto check_record = [&](const RayRecord& rec, const std::string& what) {
    const bool from_a = rec.source == Side::a;
    const Shape& source = from_a ? a : b;
    const Shape& target = from_a ? b : a;
    require(rec.source_body == (from_a ? pair.a : pair.b) && rec.target_body == (from_a ? pair.b : pair.a),
            where + what + ": source/target bodies do not match the side");
    require(rec.vertex < source.sources().origins.size(),
            where + what + ": vertex " + std::to_string(rec.vertex) + " >= source origin count " +
                std::to_string(source.sources().origins.size()));
    require(rec.triangle >= 0 && size_t(rec.triangle) < face_count(target),
            where + what + ": triangle " + std::to_string(rec.triangle) + " outside the target's " +
                std::to_string(face_count(target)) + " faces");
    require(rec.origin.allFinite(), where + what + ": non-finite origin");
    require(unit(rec.direction), where + what + ": direction not finite and unit");
    require(unit(rec.normal), where + what + ": normal not finite and unit");
  };

  double max_depth = 0.0;
  for (const Contact& c : r.contacts) {
    const std::string what = "contact of vertex " + std::to_string(c.vertex) + " (depth " +
                             num(c.depth) + ", projected " + num(c.projected_depth) + ")";
    check_record(c, what);
    require(std::isfinite(c.depth) && c.depth >= 0.0, where + what + ": depth not finite and >= 0");
    // |direction . normal| <= 1 up to rounding of two unit vectors.
    require(std::isfinite(c.projected_depth) && c.projected_depth >= 0.0 &&
                c.projected_depth <= c.depth * (1.0 + 1e-9),
            where + what + ": projected depth not in [0, depth]");
    require(c.push.allFinite(), where + what + ": non-finite push");
    max_depth = std::max(max_depth, c.depth);
  }
  require(p.max_depth == max_depth, where + "max_depth is not the largest contact depth");
  for (const PredictiveRay& q : r.predictive) {
    const std::string what = "predictive ray of vertex " + std::to_string(q.vertex) + " (distance " +
                             num(q.distance) + ")";
    check_record(q, what);
    require(std::isfinite(q.distance) && q.distance >= 0.0, where + what + ": distance not finite and >= 0");
  }
}

// (source, vertex) of every penetrating vertex ray.
inline std::set<std::pair<int, uint32_t>> penetrating(const StepResult& r) {
  std::set<std::pair<int, uint32_t>> s;
  for (const Contact& c : r.contacts)
    if (c.kind == ContactKind::vertex) s.insert({int(c.source), c.vertex});
  return s;
}

// Distance from contact c's ray origin (the source vertex) to the target's
// surface: near zero the vertex lies on the target, where inside and outside
// are a tie (for a mesh target; infinite for a volume).
inline double origin_distance_to_surface(const Contact& c, const Shape& target, const Pose& target_pose) {
  const Mesh* m = target.mesh();
  if (m == nullptr) return std::numeric_limits<double>::infinity();
  const Eigen::Vector3d p = target_pose.inverse().apply(c.origin);
  double best = std::numeric_limits<double>::infinity();
  for (const auto& tri : m->triangles()) {
    const auto v = [&](int k) { return m->positions()[tri[k]].cast<double>(); };
    best = std::min(best, (p - closest_on_triangle(p, v(0), v(1), v(2))).norm());
  }
  return best;
}

// How close contact c's ray, from its origin to `reach` past where it
// leaves the target, passes to an edge or vertex of the target mesh
// (infinite for a volume). Near zero the ray goes through an edge or vertex,
// where the faces that meet there tie for the first hit (or, on an open
// mesh's rim, the hit is on the boundary): backends may break that tie
// differently. The reach covers depths taken from the plane of a triangle
// nearly parallel to the ray, which can fall well short of the crossing.
inline double ray_distance_to_edges(const Contact& c, const Shape& target, const Pose& target_pose, double reach) {
  const Mesh* m = target.mesh();
  if (m == nullptr) return std::numeric_limits<double>::infinity();
  const Pose to_local = target_pose.inverse();
  const Eigen::Vector3d p0 = to_local.apply(c.origin);
  const Eigen::Vector3d p1 = p0 + (c.depth + reach) * (to_local.orientation * c.direction);
  double best = std::numeric_limits<double>::infinity();
  for (const auto& tri : m->triangles())
    for (int e = 0; e < 3; ++e)
      best = std::min(best, segment_distance(p0, p1, m->positions()[tri[e]].cast<double>(),
                                             m->positions()[tri[(e + 1) % 3]].cast<double>()));
  return best;
}

// Distance from where contact c's ray leaves the target to the nearest
// other triangle of the target: near zero two faces meet or overlap at the
// exit (a self-overlapping mesh, or an edge) and tie for the first hit.
inline double exit_distance_to_other_faces(const Contact& c, const Shape& target, const Pose& target_pose) {
  const Mesh* m = target.mesh();
  if (m == nullptr) return std::numeric_limits<double>::infinity();
  const Pose to_local = target_pose.inverse();
  const Eigen::Vector3d exit = to_local.apply(c.origin) + c.depth * (to_local.orientation * c.direction);
  double best = std::numeric_limits<double>::infinity();
  for (size_t t = 0; t < m->triangle_count(); ++t) {
    if (int32_t(t) == c.triangle) continue;
    const auto v = [&](int k) { return m->positions()[m->triangles()[t][k]].cast<double>(); };
    best = std::min(best, (exit - closest_on_triangle(exit, v(0), v(1), v(2))).norm());
  }
  return best;
}

// Two backends in a full step see the same penetrating vertices. A vertex
// only one of them reports is excused when its depth is within `band`, or
// when `tie(contact)` says it is a tie the tracers may break differently: the
// vertex lies on the target's surface, its ray passes through an edge or
// vertex of the target, or it leaves where two faces meet or overlap (see
// fuzz/README.md). RTCD_FUZZ_STRICT=1 excuses only the depth band.
template <class Tie>
void check_same_contacts(const std::string& name_x, const StepResult& x, const std::string& name_y,
                         const StepResult& y, double band, Tie tie) {
  static const bool strict = std::getenv("RTCD_FUZZ_STRICT") != nullptr;
  auto one_way = [&](const std::string& has, const StepResult& r, const std::string& lacks, const StepResult& other) {
    const auto theirs = penetrating(other);
    for (const Contact& c : r.contacts)
      if (c.kind == ContactKind::vertex && !theirs.contains({int(c.source), c.vertex}) && !(c.depth <= band) &&
          (strict || !tie(c)))
        violated(has + " reports vertex " + std::to_string(c.vertex) + " of body " +
                 (c.source == Side::a ? "a" : "b") + " penetrating at depth " + num(c.depth) + " (triangle " +
                 std::to_string(c.triangle) + "), " + lacks + " does not (band " + num(band) + ")");
  };
  one_way(name_x, x, name_y, y);
  one_way(name_y, y, name_x, x);
}

}  // namespace rtcd::fuzz
