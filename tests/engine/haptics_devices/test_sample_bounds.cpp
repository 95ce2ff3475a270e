// The bounds a device sample meets before the physics (engine/haptics/sample_bounds.hpp): kept
// untouched inside, grip and pedal clamped, a non-finite or out-of-workspace sample dropped; the
// recorder keeps only what passes. The session applies the same check to every device kind
// (tests/procedures/haptics/test_haptic_session.cpp).
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "engine/haptics/replay_device.hpp"
#include "engine/haptics/sample_bounds.hpp"

namespace phaco {
namespace {

DeviceSample inside() {
  DeviceSample s;
  s.t_ns = 1000;
  s.seq = 1;
  s.pos_mm = Vec3(12.5, -3.25, 7.0);
  s.quat = Quat(Eigen::AngleAxisd(0.7, Vec3(1, 2, 3).normalized()));
  s.grip = 0.4;
  s.pedal = 2.5;
  return s;
}

bool same(const DeviceSample& a, const DeviceSample& b) {
  return a.t_ns == b.t_ns && a.seq == b.seq && a.pos_mm == b.pos_mm &&
         a.quat.coeffs() == b.quat.coeffs() && a.grip == b.grip && a.pedal == b.pedal &&
         a.buttons == b.buttons;
}

TEST(SampleBounds, InsideIsKeptBitForBit) {
  DeviceSample s = inside();
  EXPECT_EQ(bound_sample(s), SampleCheck::Ok);
  EXPECT_TRUE(same(s, inside()));
  // The workspace's faces belong to it.
  for (double edge : {kWorkspaceHalfMm, -kWorkspaceHalfMm}) {
    for (int axis = 0; axis < 3; ++axis) {
      DeviceSample e = inside();
      e.pos_mm[axis] = edge;
      EXPECT_EQ(bound_sample(e), SampleCheck::Ok) << "axis " << axis << " at " << edge;
    }
  }
  DeviceSample ends = inside();
  ends.grip = kMaxGrip, ends.pedal = 0;
  EXPECT_EQ(bound_sample(ends), SampleCheck::Ok);
}

TEST(SampleBounds, OutsideTheWorkspaceIsDroppedAndLeftAlone) {
  constexpr double kInf = std::numeric_limits<double>::infinity();
  for (double x : {std::nextafter(kWorkspaceHalfMm, kInf), -50.5, 1.2e19, -1e300, 1e308}) {
    for (int axis = 0; axis < 3; ++axis) {
      DeviceSample s = inside();
      s.pos_mm[axis] = x;
      s.grip = 7;  // would be clamped, but the whole sample goes
      const DeviceSample before = s;
      EXPECT_EQ(bound_sample(s), SampleCheck::OutsideWorkspace) << "axis " << axis << " at " << x;
      EXPECT_TRUE(same(s, before)) << "a dropped sample is not modified";
    }
  }
}

TEST(SampleBounds, NonFiniteOrNoRotationIsDropped) {
  constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
  constexpr double kInf = std::numeric_limits<double>::infinity();
  const auto check = [](auto&& spoil) {
    DeviceSample s = inside();
    spoil(s);
    return bound_sample(s);
  };
  for (double bad : {kNaN, kInf, -kInf}) {
    EXPECT_EQ(check([&](DeviceSample& s) { s.pos_mm.y() = bad; }), SampleCheck::NonFinite);
    EXPECT_EQ(check([&](DeviceSample& s) { s.quat.x() = bad; }), SampleCheck::NonFinite);
    EXPECT_EQ(check([&](DeviceSample& s) { s.grip = bad; }), SampleCheck::NonFinite);
    EXPECT_EQ(check([&](DeviceSample& s) { s.pedal = bad; }), SampleCheck::NonFinite);
  }
  EXPECT_EQ(check([](DeviceSample& s) { s.quat.coeffs().setZero(); }), SampleCheck::NonFinite);
  EXPECT_EQ(check([](DeviceSample& s) { s.quat.coeffs().setConstant(1e-9); }),
            SampleCheck::NonFinite);
  // Finite components whose norm overflows.
  EXPECT_EQ(check([](DeviceSample& s) { s.quat.coeffs().setConstant(1e200); }),
            SampleCheck::NonFinite);
}

TEST(SampleBounds, GripAndPedalAreClampedTheRestKept) {
  DeviceSample s = inside();
  s.grip = 1.5, s.pedal = -0.25;
  EXPECT_EQ(bound_sample(s), SampleCheck::Clamped);
  EXPECT_EQ(s.grip, kMaxGrip);
  EXPECT_EQ(s.pedal, 0.0);
  EXPECT_EQ(s.pos_mm, inside().pos_mm);
  s.grip = -3, s.pedal = 1e9;
  EXPECT_EQ(bound_sample(s), SampleCheck::Clamped);
  EXPECT_EQ(s.grip, 0.0);
  EXPECT_EQ(s.pedal, kMaxPedal);
}

TEST(SampleBounds, ANonUnitQuaternionIsRenormalised) {
  DeviceSample s = inside();
  s.quat.coeffs() *= 3.0;
  EXPECT_EQ(bound_sample(s), SampleCheck::Ok);
  EXPECT_NEAR(s.quat.norm(), 1.0, 1e-15);
  EXPECT_TRUE(s.quat.isApprox(inside().quat, 1e-15));
}

TEST(SampleBounds, TheRecorderKeepsOnlyWhatPasses) {
  DeviceRecorder rec(16);
  DeviceSample s = inside();
  ASSERT_TRUE(rec.record(s));
  s.seq = 2, s.t_ns += 1000, s.pos_mm.x() = 1e19;
  EXPECT_FALSE(rec.record(s));
  s.seq = 3, s.t_ns += 1000, s.pos_mm.x() = std::numeric_limits<double>::quiet_NaN();
  EXPECT_FALSE(rec.record(s));
  s.seq = 4, s.t_ns += 1000, s.pos_mm.x() = 49.0, s.pedal = 9;
  ASSERT_TRUE(rec.record(s));
  EXPECT_EQ(rec.size(), 2u);
  EXPECT_EQ(rec.rejected(), 2u);
  EXPECT_EQ(rec.samples()[1].pos.x(), 49.0);
  EXPECT_EQ(rec.samples()[1].pedal, kMaxPedal);
}

}  // namespace
}  // namespace phaco
