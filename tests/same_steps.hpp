// Steps of a family's pairs, and their comparison bit for bit: shared by
// the tests that hold two runs to the same output (a device against the
// CPU, thread counts, repeats).
#pragma once

#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "rtcd/backend.hpp"
#include "rtcd/narrow_phase.hpp"
#include "rtcd/validation/families.hpp"

namespace rtcd::test {

// Pairs of a family stepped together, B moving a little each step: every
// step is one batch of many jobs (spread over the devices of a device
// backend, over the threads of a CPU one).
struct Scene {
  std::string family;
  Mode mode;
  size_t pairs = 16;
  size_t steps = 4;
  uint64_t seed = 7;
  Config config = {};  // every knob but the mode
  double motion_scale = 1.0;  // times the family's step motion
};

inline std::vector<StepResult> run_scene(const std::string& backend, const Scene& s) {
  const validation::Family f = validation::make_family(s.family);
  Config config = s.config;
  config.mode = s.mode;
  auto narrow = make_narrow_phase(backend, config);
  const ShapeId sa = narrow->add_shape(f.a), sb = narrow->add_shape(f.b);
  std::vector<BodyPair> pairs;
  std::vector<validation::PosePair> poses;
  for (size_t i = 0; i < s.pairs; ++i) {
    poses.push_back(validation::random_poses(f, s.seed, i));
    pairs.push_back({narrow->add_body(sa, poses[i].a), narrow->add_body(sb, poses[i].b)});
  }
  std::vector<StepResult> results;
  for (size_t step = 0; step < s.steps; ++step) {
    for (size_t i = 0; i < s.pairs; ++i) {
      if (step > 0) poses[i] = validation::moved(f, poses[i], s.motion_scale * f.step_motion(), s.seed, step * s.pairs + i);
      narrow->set_pose(pairs[i].a, poses[i].a);
      narrow->set_pose(pairs[i].b, poses[i].b);
    }
    results.push_back(narrow->detect(pairs));
  }
  return results;
}

inline void expect_same_record(const RayRecord& x, const RayRecord& y) {
  EXPECT_EQ(x.source, y.source);
  EXPECT_EQ(x.source_body, y.source_body);
  EXPECT_EQ(x.target_body, y.target_body);
  EXPECT_EQ(x.vertex, y.vertex);
  EXPECT_EQ(x.triangle, y.triangle) << "vertex " << x.vertex;
  EXPECT_EQ(x.origin, y.origin);
  EXPECT_EQ(x.direction, y.direction);
  EXPECT_EQ(x.normal, y.normal);
}

// Everything a step reports, bit for bit, but the clock readings and where
// the rays ran (expect_same_placement).
inline void expect_same_step(const StepResult& x, const StepResult& y, const std::string& where) {
  SCOPED_TRACE(where);
  ASSERT_EQ(x.pairs.size(), y.pairs.size());
  for (size_t i = 0; i < x.pairs.size(); ++i) {
    EXPECT_EQ(x.pairs[i].pair.a, y.pairs[i].pair.a) << "pair " << i;
    EXPECT_EQ(x.pairs[i].pair.b, y.pairs[i].pair.b) << "pair " << i;
    EXPECT_EQ(x.pairs[i].colliding, y.pairs[i].colliding) << "pair " << i;
    EXPECT_EQ(x.pairs[i].mode, y.pairs[i].mode) << "pair " << i;
    EXPECT_EQ(x.pairs[i].max_depth, y.pairs[i].max_depth) << "pair " << i;
    EXPECT_EQ(x.pairs[i].first_contact, y.pairs[i].first_contact) << "pair " << i;
    EXPECT_EQ(x.pairs[i].contact_count, y.pairs[i].contact_count) << "pair " << i;
    EXPECT_EQ(x.pairs[i].first_predictive, y.pairs[i].first_predictive) << "pair " << i;
    EXPECT_EQ(x.pairs[i].predictive_count, y.pairs[i].predictive_count) << "pair " << i;
  }
  ASSERT_EQ(x.contacts.size(), y.contacts.size());
  for (size_t k = 0; k < x.contacts.size(); ++k) {
    expect_same_record(x.contacts[k], y.contacts[k]);
    EXPECT_EQ(x.contacts[k].kind, y.contacts[k].kind);
    EXPECT_EQ(x.contacts[k].edge, y.contacts[k].edge);
    EXPECT_EQ(x.contacts[k].depth, y.contacts[k].depth);
    EXPECT_EQ(x.contacts[k].projected_depth, y.contacts[k].projected_depth);
    EXPECT_EQ(x.contacts[k].push, y.contacts[k].push);
  }
  ASSERT_EQ(x.predictive.size(), y.predictive.size());
  for (size_t k = 0; k < x.predictive.size(); ++k) {
    expect_same_record(x.predictive[k], y.predictive[k]);
    EXPECT_EQ(x.predictive[k].distance, y.predictive[k].distance);
  }
  const StepStats &a = x.stats, &b = y.stats;
  EXPECT_EQ(a.pairs_full, b.pairs_full);
  EXPECT_EQ(a.pairs_iterative, b.pairs_iterative);
  EXPECT_EQ(a.fallbacks_to_full, b.fallbacks_to_full);
  EXPECT_EQ(a.pairs_certified, b.pairs_certified);
  EXPECT_EQ(a.certificates_granted, b.certificates_granted);
  EXPECT_EQ(a.certificates_expired, b.certificates_expired);
  EXPECT_EQ(a.candidates, b.candidates);
  EXPECT_EQ(a.rays_full, b.rays_full);
  EXPECT_EQ(a.rays_predictive, b.rays_predictive);
  EXPECT_EQ(a.rays_iterative, b.rays_iterative);
  EXPECT_EQ(a.walk_steps, b.walk_steps);
  EXPECT_EQ(a.nearest_queries, b.nearest_queries);
  EXPECT_EQ(a.rays_retraced, b.rays_retraced);
  EXPECT_EQ(a.rays_watched, b.rays_watched);
  EXPECT_EQ(a.fold_casts, b.fold_casts);
  EXPECT_EQ(a.walk_endings, b.walk_endings);
  EXPECT_EQ(a.edges_tested, b.edges_tested);
  EXPECT_EQ(a.edges_skipped, b.edges_skipped);
  EXPECT_EQ(a.edge_rays, b.edge_rays);
  EXPECT_EQ(a.edge_contacts, b.edge_contacts);
}

// Where two runs of one backend sent their rays: the same bytes to and from
// each device, the same jobs, rays, commands and waits on each, the same
// fallback.
inline void expect_same_placement(const StepStats& a, const StepStats& b, const std::string& where) {
  SCOPED_TRACE(where);
  EXPECT_EQ(a.bytes_to_device, b.bytes_to_device);
  EXPECT_EQ(a.bytes_from_device, b.bytes_from_device);
  EXPECT_EQ(a.bytes_recovery, b.bytes_recovery);
  ASSERT_EQ(a.devices.size(), b.devices.size());
  for (size_t d = 0; d < a.devices.size(); ++d) {
    EXPECT_EQ(a.devices[d].jobs, b.devices[d].jobs) << "device " << d;
    EXPECT_EQ(a.devices[d].rays, b.devices[d].rays) << "device " << d;
    EXPECT_EQ(a.devices[d].launches, b.devices[d].launches) << "device " << d;
    EXPECT_EQ(a.devices[d].writes, b.devices[d].writes) << "device " << d;
    EXPECT_EQ(a.devices[d].reads, b.devices[d].reads) << "device " << d;
    EXPECT_EQ(a.devices[d].waits, b.devices[d].waits) << "device " << d;
  }
  EXPECT_EQ(a.cpu_fallback, b.cpu_fallback);
}

// Two runs step by step; returns the rays the second reported (contacts and
// predictive), so a caller can tell the comparison was not vacuous.
inline size_t expect_same_run(const std::vector<StepResult>& x, const std::vector<StepResult>& y) {
  EXPECT_EQ(x.size(), y.size());
  size_t reported = 0;
  for (size_t s = 0; s < std::min(x.size(), y.size()); ++s) {
    expect_same_step(x[s], y[s], "step " + std::to_string(s));
    reported += y[s].contacts.size() + y[s].predictive.size();
  }
  return reported;
}

}  // namespace rtcd::test
