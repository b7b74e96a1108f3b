// libFuzzer harness: two small bodies (meshes from raw triangles, generator
// meshes with moved vertices, or a sphere/box), two poses and a Config built
// from the input, stepped 2-3 times on every usable CPU backend. Checks the
// invariants of fuzz/invariants.hpp each step, that basic and embree find
// the same penetrating vertices in every full step, and that a pair FCL and
// the exact reference find interpenetrating is colliding in every full step.
//
// Input layout: fuzz/pair_input.hpp.
#include <cstdio>
#include <cstdlib>
#include <tuple>

#include <tbb/global_control.h>

#include "invariants.hpp"
#include "pair_input.hpp"
#include "rtcd/mesh_check.hpp"
#include "rtcd/oracle/exact.hpp"
#include "rtcd/oracle/third_party.hpp"

namespace {

using namespace rtcd;

// Results never depend on the thread count; one thread keeps the fuzzer
// fast on a shared machine and crashes easy to read.
tbb::global_control one_thread(tbb::global_control::max_allowed_parallelism, 1);

const bool verbose = std::getenv("RTCD_FUZZ_VERBOSE") != nullptr;

// A body whose inside is defined: a volume, or a mesh the checker finds fit
// and closed, with no face crossing another.
bool solid(const Shape& s) {
  const Mesh* m = s.mesh();
  if (m == nullptr) return !std::holds_alternative<HalfSpace>(s.geometry());
  const MeshCheck check = check_mesh(m->positions(), m->triangles());
  return check.fit() && check.closed && self_intersections(m->positions(), m->triangles(), 1).empty();
}

// Whether the exact reference finds either body inside the other deeper
// than `band`: an origin, or an edge crossing with no origin inside.
bool interpenetrate(const std::shared_ptr<const Shape>& a, const Pose& pa, const std::shared_ptr<const Shape>& b,
                    const Pose& pb, double band) {
  const oracle::ExactShape ea(a), eb(b);
  for (const auto& [source, source_pose, target, target_pose] :
       {std::tuple{a.get(), &pa, &eb, &pb}, std::tuple{b.get(), &pb, &ea, &pa}}) {
    for (const oracle::ExactRay& r : target->rays_from(*source, *source_pose, *target_pose, band))
      if (r.deep()) return true;
    for (double depth : target->edge_depths(*source, *source_pose, *target_pose))
      if (depth > band) return true;
    if (target->sphere_depth(*source, *source_pose, *target_pose) > band) return true;
  }
  return false;
}

// A vertex contact as its ray saw it: along the vertex's inward normal to
// the target's first hit. A contact measured to the nearest surface
// (Config::nearest_surface) keeps the vertex but not its ray, which the tie
// rules below judge.
Contact along_ray(const Contact& c, const Shape& source, const Pose& source_pose, const oracle::ExactShape& target,
                  const Pose& target_pose) {
  Contact r = c;
  if (c.kind != ContactKind::vertex) return r;
  r.direction = source_pose.orientation * source.sources().directions[c.vertex].cast<double>().normalized();
  const Pose to_local = target_pose.inverse();
  double t = 0;
  int32_t triangle = -1;
  if (target.first_hit(to_local.apply(c.origin), to_local.orientation * r.direction, t, triangle)) {
    r.depth = t;
    r.triangle = triangle;
  }
  return r;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t length) {
  const auto input = fuzz::read_pair_case(data, length);
  if (!input) return 0;
  // Named references, not a structured binding: lambdas below capture them.
  const std::shared_ptr<const Shape>&shape_a = input->shape_a, &shape_b = input->shape_b;
  const std::vector<Pose>&poses_a = input->poses_a, &poses_b = input->poses_b;
  const int steps = input->steps;

  // Length scale of the pair: tolerances below are relative to it.
  const double size = std::max(fuzz::size_of(*shape_a), fuzz::size_of(*shape_b));
  const double band = 1e-4 * size;

  // The CPU backends only: the OpenCL one has its own harness (fuzz/opencl.cpp)
  // with one context for the whole run.
  static const std::vector<std::string> backends = fuzz::cpu_backends();
  std::vector<std::vector<StepResult>> results;
  for (const std::string& backend : backends) results.push_back(fuzz::run_pair_case(*input, backend));
  const oracle::ExactShape exact_a(shape_a), exact_b(shape_b);
  const auto ray_of = [&](const Contact& c, int s) {
    const bool on_b = c.source == Side::a;
    return along_ray(c, on_b ? *shape_a : *shape_b, on_b ? poses_a[s] : poses_b[s], on_b ? exact_b : exact_a,
                     on_b ? poses_b[s] : poses_a[s]);
  };
  if (verbose) {
    for (size_t k = 0; k < backends.size(); ++k)
      for (int s = 0; s < steps; ++s) {
        const StepResult& out = results[k][s];
        std::fprintf(stderr, "%s step %d: %s, %zu contacts, %zu predictive\n", backends[k].c_str(), s,
                     to_string(out.pairs[0].mode), out.contacts.size(), out.predictive.size());
        for (const Contact& c : out.contacts) {
          const bool on_b = c.source == Side::a;
          const Shape& target = on_b ? *shape_b : *shape_a;
          const Pose& target_pose = on_b ? poses_b[s] : poses_a[s];
          std::fprintf(stderr,
                       "  %c vertex %u triangle %d depth %.9g; vertex %.3g from the surface, ray %.3g from an edge, "
                       "exit %.3g from another face\n",
                       c.source == Side::a ? 'a' : 'b', c.vertex, c.triangle, c.depth,
                       fuzz::origin_distance_to_surface(c, target, target_pose),
                       fuzz::ray_distance_to_edges(ray_of(c, s), target, target_pose, size),
                       fuzz::exit_distance_to_other_faces(ray_of(c, s), target, target_pose));
        }
      }
  }

  // Full steps do not depend on earlier results, so backends must agree there.
  for (size_t k = 1; k < backends.size(); ++k)
    for (int s = 0; s < steps; ++s) {
      const StepResult &x = results[0][s], &y = results[k][s];
      fuzz::require(x.pairs[0].mode == y.pairs[0].mode, "step " + std::to_string(s) + ": " + backends[0] + " and " +
                                                            backends[k] + " chose different pair modes");
      // A vertex within the band of the target's surface; a ray through one
      // of its edges or vertices, or leaving where a second face meets the
      // exit, up to float rounding of the ray.
      auto tie = [&](const Contact& c) {
        const bool on_b = c.source == Side::a;
        const Shape& target = on_b ? *shape_b : *shape_a;
        const Pose& target_pose = on_b ? poses_b[s] : poses_a[s];
        const double rounding = 1e-5 * (size + (c.origin - target_pose.position).norm());
        const Contact ray = ray_of(c, s);
        return fuzz::origin_distance_to_surface(c, target, target_pose) <= band ||
               fuzz::ray_distance_to_edges(ray, target, target_pose, size) <= rounding ||
               fuzz::exit_distance_to_other_faces(ray, target, target_pose) <= rounding;
      };
      if (x.pairs[0].mode == PairMode::full)
        fuzz::check_same_contacts(backends[0] + " step " + std::to_string(s), x, backends[k], y, band, tie);
    }
  // Every pair that truly interpenetrates is reported: in a full step with
  // edge contacts on, FCL colliding (triangles crossing) means colliding,
  // unless the exact reference finds nothing deeper than the band (touching).
  if (input->config.edge_contacts && solid(*shape_a) && solid(*shape_b)) {
    const oracle::FclShape fcl_a(*shape_a), fcl_b(*shape_b);
    for (int s = 0; s < steps; ++s) {
      const StepResult& x = results[0][s];
      if (x.pairs[0].mode != PairMode::full || x.pairs[0].colliding) continue;
      if (!fcl_a.collide(poses_a[s], fcl_b, poses_b[s]).colliding) continue;
      fuzz::require(!interpenetrate(shape_a, poses_a[s], shape_b, poses_b[s], band),
                    "step " + std::to_string(s) + ": FCL and the exact reference find the bodies interpenetrating "
                    "deeper than " + fuzz::num(band) + ", " + backends[0] + " calls them separate");
    }
  }
  return 0;
}
