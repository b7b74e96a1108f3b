// A full job's candidates (visit_near_items): the distance bound turns away
// leaves of edges far from the target's surface, and never one holding an
// edge within the reach, measured exactly (segment to triangle, in double).
#include <cmath>
#include <random>

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include "rtcd/cpu_executor.hpp"
#include "rtcd/distance_bound.hpp"
#include "rtcd/mesh_gen.hpp"
#include "rtcd/near_search.hpp"

namespace rtcd {
namespace {

// Whether segment [p, q] meets triangle (a, b, c) (Moller-Trumbore, double).
bool segment_meets(const Eigen::Vector3d& p, const Eigen::Vector3d& q, const Eigen::Vector3d& a,
                   const Eigen::Vector3d& b, const Eigen::Vector3d& c) {
  const Eigen::Vector3d d = q - p, e1 = b - a, e2 = c - a, h = d.cross(e2);
  const double det = e1.dot(h);
  if (std::abs(det) < 1e-300) return false;
  const Eigen::Vector3d s = p - a;
  const double u = s.dot(h) / det;
  const Eigen::Vector3d k = s.cross(e1);
  const double v = d.dot(k) / det, t = e2.dot(k) / det;
  return u >= 0 && v >= 0 && u + v <= 1 && t >= 0 && t <= 1;
}

// The exact distance from segment [p, q] to a mesh's surface.
double segment_to_mesh(const Mesh& m, const Eigen::Vector3d& p, const Eigen::Vector3d& q) {
  double best = std::numeric_limits<double>::infinity();
  for (const auto& t : m.triangles()) {
    const Eigen::Vector3d a = m.positions()[t[0]].cast<double>(), b = m.positions()[t[1]].cast<double>(),
                          c = m.positions()[t[2]].cast<double>();
    if (segment_meets(p, q, a, b, c)) return 0.0;
    best = std::min({best, (closest_on_triangle(p, a, b, c) - p).norm(), (closest_on_triangle(q, a, b, c) - q).norm(),
                     segment_distance(p, q, a, b), segment_distance(p, q, b, c), segment_distance(p, q, c, a)});
  }
  return best;
}

TEST(NearLeaves, EdgesFarFromTheSurfaceAreTurnedAwayAndNoneWithinReach) {
  const Shape source(gen::concave_blob(900, 21, 0.5)), target(gen::concave_blob(900, 22, 0.5));
  const RaySources& rs = source.sources();
  const DistanceBound& bound = target.distance_bound();
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  size_t meeting = 0, visited = 0, within = 0;
  for (int trial = 0; trial < 12; ++trial) {
    RayJob job;
    job.rotation = Eigen::Quaterniond(unit(rng), unit(rng), unit(rng), unit(rng)).normalized().toRotationMatrix();
    job.translation = Eigen::Vector3d(0.8 + 0.1 * unit(rng), 0.2 * unit(rng), 0.2 * unit(rng));
    job.overlap = target.bounds().intersection(source.bounds().transformed(job.rotation, job.translation)).grown(0.05);
    const double reach = 0.02;
    std::vector<char> seen(rs.item_count(), 0);
    visit_near_items(make_frame(job), rs, bound, reach, [&](uint32_t item) { seen[item] = 1; });
    for (uint32_t e = rs.first_edge(); e < rs.item_count(); ++e) {
      const auto& ends = rs.edges[e - rs.first_edge()];
      const Eigen::Vector3d p = job.rotation * rs.origins[ends[0]].cast<double>() + job.translation;
      const Eigen::Vector3d q = job.rotation * rs.origins[ends[1]].cast<double>() + job.translation;
      const bool meets = (p.cwiseMax(q).array() >= job.overlap.min.array()).all() &&
                         (p.cwiseMin(q).array() <= job.overlap.max.array()).all();
      if (!meets) continue;
      ++meeting;
      visited += seen[e];
      if (segment_to_mesh(*target.mesh(), p, q) <= reach) {
        ++within;
        ASSERT_TRUE(seen[e]) << "trial " << trial << ": edge " << e << " within the reach was turned away";
      }
    }
    // A job that tests no edge visits none.
    std::fill(seen.begin(), seen.end(), 0);
    visit_near_items(make_frame(job), rs, bound, -1.0, [&](uint32_t item) { seen[item] = 1; });
    for (uint32_t e = rs.first_edge(); e < rs.item_count(); ++e) ASSERT_FALSE(seen[e]);
  }
  EXPECT_GT(within, 100u) << "poses in contact";
  EXPECT_LT(visited, meeting * 3 / 4) << "the bound turns away a good share of the edges in the overlap box";
}

// The search asks whether a target's distance bound at a point passes a
// threshold (rtcd_distance_exceeds), which stops at the first node that
// shows it and takes no square root for a node that cannot: the same
// answer as rtcd_distance_lower(...) > threshold, at the bound's value
// itself and one float step either side of it, within the mesh's grid and
// beyond it, and for each volume.
TEST(NearLeaves, TheSearchsThresholdTestAnswersAsTheBound) {
  const Shape shapes[] = {Shape(gen::concave_blob(900, 23, 0.5)), Shape(Sphere{0.4}),
                          Shape(Box{Eigen::Vector3d(0.3, 0.5, 0.2)}), Shape(HalfSpace{})};
  std::mt19937_64 rng(6);
  std::uniform_real_distribution<double> unit(-1.0, 1.0), spread(-0.3, 0.3);
  size_t passed = 0, not_passed = 0;
  for (const Shape& shape : shapes) {
    const DistanceBound& bound = shape.distance_bound();
    const rtcd_distance_grid grid = DistanceBoundKernel::grid(bound);
    const float* values = DistanceBoundKernel::values(bound).data();
    for (int trial = 0; trial < 4000; ++trial) {
      const double reach = trial % 4 == 0 ? 3.0 : 1.2;  // beyond the grid, or mostly within it
      const double p[3] = {reach * unit(rng), reach * unit(rng), reach * unit(rng)};
      const double lower = rtcd_distance_lower(&grid, values, p);
      for (const double threshold : {lower, std::nextafter(lower, -INFINITY), std::nextafter(lower, INFINITY),
                                     lower + spread(rng)}) {
        const bool exceeds = rtcd_distance_exceeds(&grid, values, p, threshold) != 0;
        ASSERT_EQ(exceeds, lower > threshold) << "trial " << trial << ", threshold " << threshold - lower
                                              << " from the bound " << lower;
        (exceeds ? passed : not_passed) += 1;
      }
    }
  }
  EXPECT_GT(passed, 4000u);
  EXPECT_GT(not_passed, 4000u);
}

}  // namespace
}  // namespace rtcd
