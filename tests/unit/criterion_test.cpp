// Equation 2.1 and the configuration's ranges.
#include <cmath>
#include <numbers>
#include <random>

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

// The kernel's arctangent (the devices compute equation 2.1 with it, so
// theirs and the host's are the same bits) stays within 8 ulp of the
// library's, over ratios from tiny to huge.
TEST(Criterion, KernelArctangentIsTheLibrarysToAFewUlp) {
  std::mt19937_64 g(21);
  std::uniform_real_distribution<double> unit(0.0, 1.0), exponent(-12.0, 12.0);
  double worst = 0.0;
  for (int i = 0; i < 200000; ++i) {
    const double y = unit(g) * std::pow(10.0, exponent(g)), x = unit(g);
    const double expected = std::atan2(y, x);
    const double ulp = std::nextafter(expected, 4.0) - expected;
    worst = std::max(worst, std::abs(rtcd_atan_ratio(y, x) - expected) / ulp);
  }
  EXPECT_LE(worst, 8.0);
  EXPECT_EQ(rtcd_atan_ratio(0.0, 1.0), 0.0);
  EXPECT_EQ(rtcd_atan_ratio(1.0, 0.0), std::numbers::pi / 2);
  EXPECT_EQ(rtcd_atan_ratio(2.0, 2.0), std::numbers::pi / 4);
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

// The table is the configuration: every knob reads and writes its field,
// and validate() holds each number to the table's range, naming the knob.
TEST(Config, EveryKnobOfTheTable) {
  ASSERT_EQ(rtcd::knobs().size(), 13u) << "a Config field without a knob, or a knob without a field";
  for (const rtcd::Knob& k : rtcd::knobs()) {
    SCOPED_TRACE(k.name);
    EXPECT_EQ(rtcd::find_knob(k.name), &k);
    rtcd::Config c;
    switch (k.type) {
      case rtcd::KnobType::flag:
        EXPECT_EQ(std::get<bool>(k.get(c)), true) << "switches default on";
        k.set(c, false);
        EXPECT_EQ(std::get<bool>(k.get(c)), false);
        EXPECT_THROW(k.set(c, 1.0), rtcd::ConfigError);
        break;
      case rtcd::KnobType::count:
      case rtcd::KnobType::length:
        EXPECT_TRUE(std::holds_alternative<std::monostate>(k.get(c))) << "limits default to derived";
        k.set(c, k.max);
        EXPECT_EQ(std::get<double>(k.get(c)), k.max);
        EXPECT_NO_THROW(c.validate());
        c = {};
        k.set(c, k.type == rtcd::KnobType::count ? k.max + 1 : k.max * 2);
        try {
          c.validate();
          ADD_FAILURE() << "above the range";
        } catch (const rtcd::ConfigError& e) {
          EXPECT_EQ(std::string(e.what()).rfind(k.name, 0), 0u) << e.what();
        }
        c = {};
        if (k.type == rtcd::KnobType::count) {
          EXPECT_THROW(k.set(c, 2.5), rtcd::ConfigError);
        }
        k.set(c, rtcd::KnobValue());
        EXPECT_TRUE(std::holds_alternative<std::monostate>(k.get(c)));
        break;
      case rtcd::KnobType::mode:
        EXPECT_EQ(std::get<rtcd::Mode>(k.get(c)), rtcd::Mode::automatic);
        k.set(c, rtcd::Mode::full);
        EXPECT_EQ(c.mode, rtcd::Mode::full);
        break;
    }
  }
  EXPECT_EQ(rtcd::find_knob("warp_speed"), nullptr);
  EXPECT_EQ(rtcd::to_string(rtcd::KnobValue()), "derived per pair");
}
