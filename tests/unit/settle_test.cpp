// settle_outcomes: what every executor makes of a job's outcomes before the
// host reads them.
#include <gtest/gtest.h>

#include "rtcd/step_pipeline.hpp"

namespace {

using rtcd::RayOutcome;

RayOutcome outcome(uint32_t vertex, int kind, int status = RTCD_LINE_HIT) {
  RayOutcome o{};
  o.vertex = vertex;
  o.kind = uint8_t(kind);
  o.status = uint8_t(status);
  o.walk_steps = 2;
  return o;
}

TEST(Settle, DropsWhatReportsAndTracksNothingKeepingTheOrder) {
  std::vector<RayOutcome> outcomes = {outcome(0, RTCD_RAY_DROPPED),      outcome(1, RTCD_RAY_PENETRATING),
                                      outcome(2, RTCD_RAY_DROPPED),      outcome(3, RTCD_RAY_WATCHED),
                                      outcome(4, RTCD_RAY_PREDICTIVE),   outcome(5, RTCD_RAY_DROPPED)};
  outcomes[2].predictive_cast = 1;
  outcomes[1].fold_cast = 1;
  const rtcd::RayTally full = [&] {
    auto copy = outcomes;
    return rtcd::settle_outcomes(copy, false);
  }();
  EXPECT_EQ(full.candidates, 6u);
  EXPECT_EQ(full.rays_full, 6u);
  EXPECT_EQ(full.rays_iterative, 0u);
  EXPECT_EQ(full.walk_steps, 0u);  // walks are counted for iterative jobs only

  const rtcd::RayTally t = rtcd::settle_outcomes(outcomes, true);
  ASSERT_EQ(outcomes.size(), 3u);
  EXPECT_EQ(outcomes[0].vertex, 1u);
  EXPECT_EQ(outcomes[1].vertex, 3u);
  EXPECT_EQ(outcomes[2].vertex, 4u);
  // The dropped rays still count.
  EXPECT_EQ(t.candidates, 6u);
  EXPECT_EQ(t.rays_iterative, 6u);
  EXPECT_EQ(t.rays_full, 0u);
  EXPECT_EQ(t.walk_steps, 12u);
  EXPECT_EQ(t.walk_endings[RTCD_LINE_HIT], 6u);
  EXPECT_EQ(t.contacts, 1u);
  EXPECT_EQ(t.predictive, 1u);
  EXPECT_EQ(t.rays_watched, 1u);
  EXPECT_EQ(t.rays_predictive, 1u);
  EXPECT_EQ(t.fold_casts, 1u);

  rtcd::RayTally sum = t;
  sum += full;
  EXPECT_EQ(sum.candidates, 12u);
  EXPECT_EQ(sum.rays_full, 6u);
  EXPECT_EQ(sum.rays_iterative, 6u);
  EXPECT_EQ(sum.walk_endings[RTCD_LINE_HIT], 6u);
}

TEST(Settle, KeepsEveryOutcomeOfAWalkThatDropsNone) {
  std::vector<RayOutcome> outcomes;
  for (uint32_t v = 0; v < 100; ++v) outcomes.push_back(outcome(v, v % 2 ? RTCD_RAY_PREDICTIVE : RTCD_RAY_WATCHED));
  const rtcd::RayTally t = rtcd::settle_outcomes(outcomes, true);
  ASSERT_EQ(outcomes.size(), 100u);
  for (uint32_t v = 0; v < 100; ++v) EXPECT_EQ(outcomes[v].vertex, v);
  EXPECT_EQ(t.predictive, 50u);
  EXPECT_EQ(t.rays_watched, 50u);
}

}  // namespace
