// Pairs certified apart (Config::trace_separated_pairs off): a pair the distance bounds
// prove apart costs no ray while it moves less than the proof's margin, and
// the step its motion passes the margin it is traced in full, contacts and
// all, on every usable backend.
#include <gtest/gtest.h>

#include "rtcd/mesh_gen.hpp"
#include "support.hpp"

namespace rtcd::test {
namespace {

class Certified : public ::testing::TestWithParam<std::string> {};

Config certifying(Mode mode = Mode::automatic) {
  Config c;
  c.trace_separated_pairs = false;
  c.distance_extension = 0.05;
  c.displacement_threshold = 0.02;
  c.mode = mode;
  return c;
}

TEST_P(Certified, SkippedWithinTheMarginAndTracedTheStepItPassesIt) {
  const auto a = shape(gen::concave_blob(900, 11, 0.5)), b = shape(gen::concave_blob(900, 12, 0.5));
  // B's box 0.25 beyond A's along x: the surfaces are at least that far apart.
  const double apart = a->bounds().max.x() - b->bounds().min.x() + 0.25;
  PairRig rig(GetParam(), a, b, certifying());
  const StepResult first = rig.step(Pose{}, at(apart, 0, 0));
  EXPECT_EQ(first.pairs[0].mode, PairMode::full);
  EXPECT_FALSE(first.pairs[0].colliding);
  EXPECT_EQ(first.stats.certificates_granted, 1u);

  // Moved 1 cm closer: within the margin, nothing is cast.
  const StepResult near = rig.step(Pose{}, at(apart - 0.01, 0.0, 0.0));
  EXPECT_EQ(near.pairs[0].mode, PairMode::certified);
  EXPECT_EQ(near.stats.pairs_certified, 1u);
  EXPECT_EQ(near.stats.candidates, 0u);
  EXPECT_EQ(near.stats.rays(), 0u);
  EXPECT_EQ(near.stats.edges_tested, 0u);
  EXPECT_TRUE(near.contacts.empty());
  EXPECT_TRUE(near.predictive.empty());

  // In one step B sinks 5 cm into A: past the margin, traced that step,
  // with the contacts a narrow phase that never certified finds there.
  const Pose sunk = at(apart - 0.30, 0.0, 0.0);
  const StepResult deep = rig.step(Pose{}, sunk);
  EXPECT_EQ(deep.stats.certificates_expired, 1u);
  EXPECT_EQ(deep.pairs[0].mode, PairMode::full);
  ASSERT_TRUE(deep.pairs[0].colliding) << "the crossing formed in the step the certificate expired";
  Config plain = certifying();
  plain.trace_separated_pairs = true;
  PairRig reference(GetParam(), a, b, plain);
  const StepResult expected = reference.step(Pose{}, sunk);
  EXPECT_EQ(penetrating(deep), penetrating(expected));
  EXPECT_EQ(deep.contacts.size(), expected.contacts.size());
}

// Equation 2.1 bounds the motion of the points of the body it maps, which
// must lie within the radius of its origin: a half-space's do not. A box
// 10 m from the ground's origin, turned about it by 0.02 rad, drops 20 cm
// onto the ground, while the ground's pose seen from the box moves only by
// that turn (0.02 times the box's radius): measured that way, the
// certificate would hold and the contact be lost.
TEST_P(Certified, AGroundPairsMotionIsMeasuredOnTheBoundedBody) {
  const auto box = shape(gen::box({0.3, 0.3, 0.3}));
  PairRig rig(GetParam(), std::make_shared<Shape>(HalfSpace{}), box, certifying());
  const Pose above = at(10.0, 0.0, 0.45);  // 15 cm above the ground
  const StepResult first = rig.step(Pose{}, above);
  EXPECT_FALSE(first.pairs[0].colliding);
  EXPECT_EQ(first.stats.certificates_granted, 1u);
  Pose turned;
  turned.orientation = Eigen::Quaterniond(Eigen::AngleAxisd(0.02, Eigen::Vector3d::UnitY()));
  const Pose dropped = turned * above;  // 10 sin(0.02) = 20 cm lower
  ASSERT_LT(dropped.position.z(), 0.26);
  const StepResult r = rig.step(Pose{}, dropped);
  EXPECT_EQ(r.stats.certificates_expired, 1u);
  EXPECT_EQ(r.pairs[0].mode, PairMode::full);
  EXPECT_TRUE(r.pairs[0].colliding) << "the box sank 5 cm into the ground while certified";
}

// A body wholly inside another touches no surface but is deep: its vertex
// rays report it, so it is never certified.
TEST_P(Certified, ABodyWhollyInsideIsNeverCertified) {
  PairRig rig(GetParam(), shape(gen::icosphere(1.0, 3)), shape(gen::icosphere(0.1, 2)), certifying());
  for (int k = 0; k < 3; ++k) {
    const StepResult r = rig.step(Pose{}, at(0.001 * k, 0, 0));
    EXPECT_NE(r.pairs[0].mode, PairMode::certified);
    EXPECT_TRUE(r.pairs[0].colliding);
    EXPECT_EQ(r.stats.certificates_granted, 0u);
  }
}

// Full mode stays the reference: every candidate every step.
TEST_P(Certified, FullModeCertifiesNothing) {
  const auto blob = shape(gen::concave_blob(900, 11, 0.5));
  PairRig rig(GetParam(), blob, blob, certifying(Mode::full));
  for (int k = 0; k < 3; ++k) {
    const StepResult r = rig.step(Pose{}, at(2.0 + 0.001 * k, 0, 0));
    EXPECT_EQ(r.pairs[0].mode, PairMode::full);
    EXPECT_EQ(r.stats.certificates_granted + r.stats.pairs_certified, 0u);
  }
}

// A walking pair the bounds prove apart is traced in full the next step,
// and certified there.
TEST_P(Certified, AWalkingPairThatSeparatesIsCertifiedAfterAFullTrace) {
  const auto blob = shape(gen::concave_blob(900, 11, 0.5));
  PairRig rig(GetParam(), blob, blob, certifying());
  const double touch = blob->bounds().max.x() - blob->bounds().min.x();
  ASSERT_TRUE(rig.step(Pose{}, at(touch - 0.05, 0, 0)).pairs[0].colliding);
  StepResult r;
  double x = touch - 0.05;
  // Drawn apart 1 cm a step: walking until the gap clears the extension.
  bool walked = false;
  for (int k = 1; k <= 60 && r.stats.certificates_granted == 0; ++k) {
    r = rig.step(Pose{}, at(x += 0.01, 0, 0));
    walked |= r.pairs[0].mode == PairMode::iterative && !r.pairs[0].colliding;
  }
  EXPECT_TRUE(walked) << "it walked apart before it was certified";
  EXPECT_EQ(r.stats.certificates_granted, 1u);
  EXPECT_EQ(r.pairs[0].mode, PairMode::full);
  EXPECT_EQ(rig.step(Pose{}, at(x + 0.001, 0, 0)).pairs[0].mode, PairMode::certified);
}

INSTANTIATE_TEST_SUITE_P(Backends, Certified, ::testing::ValuesIn(usable_backends()),
                         [](const auto& info) { return test_name(info.param); });

}  // namespace
}  // namespace rtcd::test
