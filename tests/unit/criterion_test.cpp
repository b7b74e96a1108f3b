// Equation 2.1 and the configuration's ranges.
#include <numbers>

#include <gtest/gtest.h>

#include "rtcd/config.hpp"
#include "rtcd/criterion.hpp"
#include "rtcd/error.hpp"

namespace {

Eigen::Quaterniond about_z(double angle) { return Eigen::Quaterniond(Eigen::AngleAxisd(angle, Eigen::Vector3d::UnitZ())); }

TEST(Criterion, AngleIsAccurateNearZeroAndNearPi) {
  EXPECT_NEAR(rtcd::rotation_angle(about_z(0), about_z(1e-9)), 1e-9, 1e-18);
  EXPECT_NEAR(rtcd::rotation_angle(about_z(0), about_z(std::numbers::pi - 1e-9)), std::numbers::pi - 1e-9, 1e-12);
  EXPECT_NEAR(rtcd::rotation_angle(about_z(0), about_z(std::numbers::pi)), std::numbers::pi, 1e-12);
  EXPECT_NEAR(rtcd::rotation_angle(about_z(0.3), about_z(0.3)), 0.0, 1e-15);
}

TEST(Criterion, QAndMinusQAreTheSameRotation) {
  const Eigen::Quaterniond q = about_z(0.7);
  const Eigen::Quaterniond minus_q(-q.w(), -q.x(), -q.y(), -q.z());
  EXPECT_NEAR(rtcd::rotation_angle(q, minus_q), 0.0, 1e-15);
  EXPECT_NEAR(rtcd::rotation_angle(about_z(0), minus_q), 0.7, 1e-12);
}

TEST(Criterion, MaxDisplacementIsTranslationPlusAngleTimesRadius) {
  rtcd::Pose before, now;
  now.position = {0.3, 0.4, 0};
  now.orientation = about_z(0.1);
  EXPECT_NEAR(rtcd::max_displacement(before, now, 2.0), 0.5 + 0.2, 1e-12);
}

TEST(Config, DefaultsAreValid) { EXPECT_NO_THROW(rtcd::Config{}.validate()); }

TEST(Config, ThresholdAboveExtensionIsAClearError) {
  rtcd::Config c;
  c.displacement_threshold = 0.2;
  c.distance_extension = 0.1;
  try {
    c.validate();
    ADD_FAILURE();
  } catch (const rtcd::ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("must not exceed distance_extension"), std::string::npos);
  }
}

TEST(Config, OutOfRangeValues) {
  rtcd::Config c;
  c.max_walk_steps = 0;
  EXPECT_THROW(c.validate(), rtcd::ConfigError);
  c = {};
  c.distance_extension = -1;
  EXPECT_THROW(c.validate(), rtcd::ConfigError);
  c = {};
  c.displacement_threshold = std::nan("");
  EXPECT_THROW(c.validate(), rtcd::ConfigError);
  EXPECT_THROW(rtcd::parse_mode("sometimes"), rtcd::ConfigError);
  EXPECT_EQ(rtcd::parse_mode("auto"), rtcd::Mode::automatic);
}

TEST(Pose, CheckedRejectsNonFiniteAndNonUnit) {
  rtcd::Pose p;
  p.position.x() = std::nan("");
  EXPECT_THROW(rtcd::checked(p), rtcd::UsageError);
  p = {};
  p.orientation = Eigen::Quaterniond(0, 0, 0, 0);
  EXPECT_THROW(rtcd::checked(p), rtcd::UsageError);
}

}  // namespace
