// The input of the pair harnesses (mesh_pair, opencl): two small bodies
// (meshes from raw triangles, generator meshes with moved vertices, or a
// sphere/box), two poses per step and a Config, decoded from
// FuzzedDataProvider integers (read from the end of the input);
// fuzz/make_corpus.py writes seeds in the same order. Coordinates are either
// on a 1/256 lattice (exact in float, so coplanar faces and rays through
// edges are common) or raw float/double bits.
#pragma once

#include <algorithm>
#include <array>
#include <bit>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <variant>
#include <vector>

#include <fuzzer/FuzzedDataProvider.h>

#include "invariants.hpp"
#include "rtcd/backend.hpp"
#include "rtcd/error.hpp"
#include "rtcd/mesh_gen.hpp"
#include "rtcd/narrow_phase.hpp"

namespace rtcd::fuzz {

inline constexpr uint32_t kMaxVertices = 64, kMaxTriangles = 128;

struct Reader {
  FuzzedDataProvider& in;
  bool raw = false;

  template <class T>
  T range(T lo, T hi) {
    return in.ConsumeIntegralInRange<T>(lo, hi);
  }
  bool flag() { return in.ConsumeBool(); }
  // A mesh coordinate or length.
  float coord() {
    if (raw) return std::bit_cast<float>(in.ConsumeIntegral<uint32_t>());
    return float(range<int16_t>(-2048, 2047)) / 256.0f;
  }
  // A pose component: position in [-16, 16) on the lattice.
  double position() {
    if (raw) return std::bit_cast<double>(in.ConsumeIntegral<uint64_t>());
    return range<int16_t>(-4096, 4095) / 256.0;
  }
  double quaternion_component() {
    if (raw) return std::bit_cast<double>(in.ConsumeIntegral<uint64_t>());
    return range<int8_t>(-128, 127);
  }
};

// Moves a few vertices of a generated mesh: same topology, new geometry.
inline Mesh perturbed(Reader& r, const Mesh& m, const MeshOptions& options) {
  std::vector<Eigen::Vector3f> p(m.positions().begin(), m.positions().end());
  std::vector<Mesh::Triangle> t(m.triangles().begin(), m.triangles().end());
  const int moves = r.range<uint8_t>(0, 8);
  for (int i = 0; i < moves; ++i) {
    const size_t v = r.range<uint8_t>(0, 255) % p.size();
    for (int k = 0; k < 3; ++k) p[v][k] += r.coord() / 16.0f;
  }
  return Mesh(std::move(p), std::move(t), options);
}

// One body's shape, or nothing when the input names an invalid one
// (MeshError, or generator parameters outside their documented range).
inline std::shared_ptr<const Shape> read_shape(Reader& r) {
  const int kind = r.range<uint8_t>(0, 9);
  MeshOptions options;
  options.allow_zero_area = r.flag();
  try {
    if (kind <= 2) {
      const uint32_t nv = r.range<uint32_t>(3, kMaxVertices), nt = r.range<uint32_t>(1, kMaxTriangles);
      std::vector<Eigen::Vector3f> positions(nv);
      for (auto& p : positions) p = {r.coord(), r.coord(), r.coord()};
      std::vector<Mesh::Triangle> triangles(nt);
      // Indices up to 63 whatever nv is: out-of-range indices get exercised too.
      for (auto& t : triangles) t = {r.range<uint8_t>(0, 63), r.range<uint8_t>(0, 63), r.range<uint8_t>(0, 63)};
      return std::make_shared<Shape>(Mesh(std::move(positions), std::move(triangles), options));
    }
    if (kind == 9) {
      if (r.flag()) {
        const double radius = std::abs(double(r.coord()));
        const double density = r.raw ? 0.0 : r.range<uint8_t>(0, 3) * 0.25;
        if (!(radius > 0) || !std::isfinite(radius)) return nullptr;
        return std::make_shared<Shape>(Sphere{radius}, density);
      }
      const Eigen::Vector3d h{std::abs(r.coord()), std::abs(r.coord()), std::abs(r.coord())};
      if (!h.allFinite() || (h.array() <= 0).any()) return nullptr;
      return std::make_shared<Shape>(Box{h});
    }
    std::optional<Mesh> m;
    switch (kind) {
      case 3: m = gen::box({r.coord(), r.coord(), r.coord()}); break;
      case 4: {
        const double radius = r.coord();
        m = gen::icosphere(radius, r.range<uint8_t>(0, 1));
        break;
      }
      case 5: {
        const double minor = std::abs(double(r.coord()));
        const double major = minor + std::abs(double(r.coord()));
        const int nu = r.range<uint8_t>(3, 8), nv = r.range<uint8_t>(3, 8);
        if (!(minor > 0) || !(major > minor) || !std::isfinite(major)) return nullptr;
        m = gen::torus(major, minor, nu, nv);
        break;
      }
      case 6: {
        const int triangles = 2 * r.range<uint8_t>(4, kMaxTriangles / 2);
        const uint32_t seed = r.in.ConsumeIntegral<uint32_t>();
        m = gen::concave_blob(triangles, seed, r.coord());
        break;
      }
      case 7: {
        const int n = r.range<uint8_t>(1, 7);
        const double size = r.coord();
        m = gen::open_sheet(n, size, r.coord());
        break;
      }
      default: {
        const double scale = r.coord();
        m = gen::u_shape(scale, r.coord());
        break;
      }
    }
    if (r.flag()) m = perturbed(r, *m, options);
    return std::make_shared<Shape>(std::move(*m));
  } catch (const MeshError&) {
    return nullptr;  // invalid meshes are rejected by design
  } catch (const UsageError&) {
    return nullptr;  // so are volumes outside the supported sizes
  }
}

// A pose, or nothing when its quaternion cannot be normalised.
inline std::optional<Pose> read_pose(Reader& r) {
  Pose p;
  p.position = {r.position(), r.position(), r.position()};
  Eigen::Quaterniond q{r.quaternion_component(), r.quaternion_component(), r.quaternion_component(),
                       r.quaternion_component()};
  const double norm = q.norm();
  if (!p.position.allFinite() || !std::isfinite(norm) || !(norm > 0)) return std::nullopt;
  q.coeffs() /= norm;
  if (!q.coeffs().allFinite() || std::abs(q.norm() - 1.0) > 1e-6) return std::nullopt;  // denormal components
  p.orientation = q;
  return p;
}

// A small motion between steps, so iterative steps walk.
inline Pose moved(Reader& r, const Pose& p) {
  Pose out = p;
  for (int k = 0; k < 3; ++k) out.position[k] += r.range<int8_t>(-128, 127) / 1024.0;
  // Braces: their elements are read in order (function arguments are not).
  const Eigen::Quaterniond turn{1.0, r.range<int8_t>(-128, 127) / 512.0, r.range<int8_t>(-128, 127) / 512.0,
                                r.range<int8_t>(-128, 127) / 512.0};
  out.orientation = (turn.normalized() * p.orientation).normalized();
  return out;
}

// A decoded case: the bodies, their poses at each step, the knobs.
struct PairCase {
  std::shared_ptr<const Shape> shape_a, shape_b;
  std::vector<Pose> poses_a, poses_b;
  Config config;
  int steps = 0;
};

inline double size_of(const Shape& s) {
  const Aabb& b = s.bounds();
  return (b.max - b.min).norm();
}

// RTCD_FUZZ_DUMP=DIR writes the decoded case (meshes as OBJ, poses and
// knobs as text) to look at a finding outside the fuzzer.
inline void dump(const std::filesystem::path& dir, const Shape& a, const Shape& b, const std::vector<Pose>& poses_a,
          const std::vector<Pose>& poses_b, const Config& c) {
  std::filesystem::create_directories(dir);
  std::FILE* f = std::fopen((dir / "case.txt").c_str(), "w");
  if (f == nullptr) return;
  for (const auto& [name, shape] : {std::pair{"a", &a}, std::pair{"b", &b}}) {
    if (const Mesh* m = shape->mesh()) {
      save_obj(*m, dir / (std::string(name) + ".obj"));
      std::fprintf(f, "%s: mesh %s.obj (%zu zero-area kept)\n", name, name, size_t(m->report().zero_area_triangles));
    } else if (const auto* s = std::get_if<Sphere>(&shape->geometry())) {
      std::fprintf(f, "%s: sphere:%.17g (%zu origins)\n", name, s->radius, shape->sources().origins.size());
    } else {
      const Eigen::Vector3d h = std::get<Box>(shape->geometry()).half_extents;
      std::fprintf(f, "%s: box:%.17g,%.17g,%.17g\n", name, h.x(), h.y(), h.z());
    }
  }
  for (size_t s = 0; s < poses_a.size(); ++s)
    for (const auto& [name, p] : {std::pair{"a", &poses_a[s]}, std::pair{"b", &poses_b[s]}})
      std::fprintf(f, "step %zu pose %s: %.17g %.17g %.17g %.17g %.17g %.17g %.17g\n", s, name, p->position.x(),
                   p->position.y(), p->position.z(), p->orientation.w(), p->orientation.x(), p->orientation.y(),
                   p->orientation.z());
  // Every knob of the table, as rtcd knobs names it.
  for (const Knob& k : knobs()) std::fprintf(f, "%s %s\n", k.name, to_string(k.get(c)).c_str());
  std::fclose(f);
}

// Every knob of the table not drawn above, from bytes after the rest, so a
// knob added to the table is fuzzed the day it is: a switch flipped from
// its default, a length set (a share of the smaller body's size, within
// its range) or left to its default. An input that ends before them keeps
// the defaults, so earlier corpora decode as they did.
inline void read_other_knobs(Reader& r, double size, Config& config) {
  static constexpr std::string_view kDrawn[] = {"max_walk_steps", "distance_extension", "displacement_threshold",
                                                "mode", "predictive", "projected"};
  for (const Knob& k : knobs()) {
    if (std::find(std::begin(kDrawn), std::end(kDrawn), k.name) != std::end(kDrawn)) continue;
    switch (k.type) {
      case KnobType::flag:
        if (r.flag()) k.set(config, !std::get<bool>(k.get(config)));
        break;
      case KnobType::length:
        if (r.flag()) k.set(config, std::clamp(size * r.range<uint16_t>(0, 65535) / 65535.0, k.min, k.max));
        break;
      case KnobType::count:
        if (r.flag()) k.set(config, double(r.range<uint32_t>(uint32_t(k.min), uint32_t(std::min(k.max, 4096.0)))));
        break;
      case KnobType::mode:
        break;
    }
  }
}

// Nothing when the input names an invalid body or pose (rejected by design).
inline std::optional<PairCase> read_pair_case(const uint8_t* data, size_t length) {
  PairCase c;
  FuzzedDataProvider in(data, length);
  Reader r{in};
  r.raw = r.flag();
  const auto shape_a = read_shape(r);
  if (!shape_a) return std::nullopt;
  const auto shape_b = read_shape(r);
  if (!shape_b) return std::nullopt;
  const auto pose_a = read_pose(r), pose_b = read_pose(r);
  if (!pose_a || !pose_b) return std::nullopt;

  // Knobs within their documented ranges, or derived per pair; the walk
  // limit stays small so one input cannot walk for seconds (a derived one is
  // at most the target's triangle count).
  Config config;
  if (r.flag()) {
    config.max_walk_steps = r.range<uint32_t>(1, 4096);
    config.distance_extension = r.range<uint32_t>(0, 1u << 20) / 4096.0;
    config.displacement_threshold = *config.distance_extension * (r.range<uint16_t>(0, 65535) / 65535.0);
  }
  config.mode = std::array{Mode::full, Mode::iterative, Mode::automatic}[r.range<uint8_t>(0, 2)];
  config.predictive = r.flag();
  config.projected = r.flag();

  const int steps = r.range<uint8_t>(2, 3);
  std::vector<Pose> poses_a{*pose_a}, poses_b{*pose_b};
  for (int s = 1; s < steps; ++s) {
    poses_a.push_back(*pose_a);
    poses_b.push_back(moved(r, poses_b.back()));
  }
  read_other_knobs(r, std::min(size_of(*shape_a), size_of(*shape_b)), config);

  c.shape_a = shape_a;
  c.shape_b = shape_b;
  c.poses_a = std::move(poses_a);
  c.poses_b = std::move(poses_b);
  c.config = config;
  c.steps = steps;
  if (const char* dir = std::getenv("RTCD_FUZZ_DUMP")) dump(dir, *c.shape_a, *c.shape_b, c.poses_a, c.poses_b, c.config);
  return c;
}

// The case stepped on one backend, every step held to check_step
// (invariants.hpp).
inline std::vector<StepResult> run_pair_case(const PairCase& c, const std::string& backend) {
  std::vector<StepResult> results;
  auto narrow = make_narrow_phase(backend, c.config);
  const ShapeId sa = narrow->add_shape(c.shape_a), sb = narrow->add_shape(c.shape_b);
  const BodyPair pair{narrow->add_body(sa, c.poses_a[0]), narrow->add_body(sb, c.poses_b[0])};
  for (int s = 0; s < c.steps; ++s) {
    narrow->set_pose(pair.a, c.poses_a[s]);
    narrow->set_pose(pair.b, c.poses_b[s]);
    StepResult& out = results.emplace_back();
    narrow->detect(std::span(&pair, 1), out);
    check_step(backend + " step " + std::to_string(s), out, pair, *c.shape_a, *c.shape_b, c.config);
  }
  return results;
}

}  // namespace rtcd::fuzz
