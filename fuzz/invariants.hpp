// What every step of the narrow phase must satisfy whatever the input:
// checks shared by the fuzz harnesses. A violation prints what broke and
// aborts, which libFuzzer reports as a crash and saves the input.
#pragma once

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <set>
#include <string>
#include <utility>

#include "rtcd/narrow_phase.hpp"

namespace rtcd::fuzz {

[[noreturn]] inline void violated(const std::string& what) {
  std::fprintf(stderr, "rtcd fuzz: invariant violated: %s\n", what.c_str());
  std::fflush(stderr);
  std::abort();
}

inline std::string num(double v) {
  char text[32];
  std::snprintf(text, sizeof text, "%.9g", v);
  return text;
}

inline void require(bool ok, const std::string& what) {
  if (!ok) violated(what);
}

// Number of faces a ray can report against `target`: triangles, box faces, 1 for a sphere.
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

// (source, vertex) of every penetrating ray, with its depth.
inline std::set<std::pair<int, uint32_t>> penetrating(const StepResult& r) {
  std::set<std::pair<int, uint32_t>> s;
  for (const Contact& c : r.contacts) s.insert({int(c.source), c.vertex});
  return s;
}

// Two backends in a full step see the same penetrating vertices; a vertex
// only one of them reports must lie within `band` of the surface (a vertex
// on a face is a tie the tracers may break either way).
inline void check_same_contacts(const std::string& name_x, const StepResult& x, const std::string& name_y,
                                const StepResult& y, double band) {
  auto one_way = [&](const std::string& has, const StepResult& r, const std::string& lacks, const StepResult& other) {
    const auto theirs = penetrating(other);
    for (const Contact& c : r.contacts)
      if (!theirs.contains({int(c.source), c.vertex}) && !(c.depth <= band))
        violated(has + " reports vertex " + std::to_string(c.vertex) + " of body " +
                 (c.source == Side::a ? "a" : "b") + " penetrating at depth " + num(c.depth) +
                 " (triangle " + std::to_string(c.triangle) + "), " + lacks + " does not (band " +
                 num(band) + ")");
  };
  one_way(name_x, x, name_y, y);
  one_way(name_y, y, name_x, x);
}

}  // namespace rtcd::fuzz
