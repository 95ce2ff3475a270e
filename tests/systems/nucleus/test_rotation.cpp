// Nucleus rotation about the optical axis (seed 000 §5.4).
#include <gtest/gtest.h>
#include <oneapi/tbb/task_arena.h>

#include <cmath>
#include <vector>

#include "systems/nucleus/rotation.hpp"

namespace phaco::nucleus {
namespace {

// Centres with small integer coordinates and m = 0.5 kg: every sum below is exact in double.
std::vector<Vec3> grid_centres() {
  std::vector<Vec3> c;
  for (int x = -3; x <= 3; ++x)
    for (int y = -2; y <= 2; ++y)
      for (int z = -1; z <= 1; ++z) c.emplace_back(x, y, z);
  return c;
}

TEST(NucleusRotation, InitialInertiaIsTheSumOfMassTimesSquaredAxisDistance) {
  const auto c = grid_centres();
  const NucleusRotation s = make_rotation(c, 0.5);
  double sum = 0;
  for (const Vec3& p : c) sum += 0.5 * (p.x() * p.x() + p.y() * p.y());
  EXPECT_EQ(s.inertia0, sum);
  EXPECT_EQ(s.inertia, sum);
  // Another axis: parallel to z through (1, 0, 0).
  const NucleusRotation off = make_rotation(c, 0.5, Axis{Vec3(1, 0, 0), Vec3(0, 0, 2)});
  double off_sum = 0;
  for (const Vec3& p : c) off_sum += 0.5 * ((p.x() - 1) * (p.x() - 1) + p.y() * p.y());
  EXPECT_EQ(off.inertia0, off_sum);
}

TEST(NucleusRotation, RemovingTetsLowersInertiaByExactlyMassTimesSquaredDistance) {
  NucleusRotation s = make_rotation(grid_centres(), 0.5);
  const double i0 = s.inertia;
  const std::vector<Vec3> first = {Vec3(3, 2, 0)};
  remove_tets(s, first);
  EXPECT_EQ(i0 - s.inertia, 0.5 * 13);
  const std::vector<Vec3> more = {Vec3(-1, 0, 1), Vec3(2, -2, -1), Vec3(0, 0, 1)};
  remove_tets(s, more);
  EXPECT_EQ(i0 - s.inertia, 0.5 * (13 + 1 + 8 + 0));
  EXPECT_EQ(s.inertia0, i0);
  // Removing everything leaves nothing to turn.
  remove_tets(s, grid_centres());
  EXPECT_EQ(s.inertia, 0.0);
  EXPECT_EQ(rotation_step(s, 100.0, RotationSettings{}, 0.01), 0.0);
}

TEST(NucleusRotation, TorqueFromTangentialProbeMotionOnly) {
  const Axis axis;
  RotationSettings s;
  s.force_per_mm = 3.0;
  // At radius 2 on +x, moving 0.1 mm along +y: F = 0.3 mN along +y, T = 2 × 0.3 = 0.6 mN·mm.
  EXPECT_NEAR(applied_torque(axis, Vec3(2, 0, 1), Vec3(2, 0.1, 1), s), 0.6, 1e-12);
  EXPECT_NEAR(applied_torque(axis, Vec3(2, 0, 1), Vec3(2, -0.1, 1), s), -0.6, 1e-12);
  EXPECT_NEAR(applied_torque(axis, Vec3(2, 0, 1), Vec3(2.3, 0, 0.5), s), 0.0,
              1e-12);  // radial, axial
}

TEST(NucleusRotation, NoRotationBelowTheDampingTorque) {
  NucleusRotation state = make_rotation(grid_centres(), 0.5);
  RotationSettings s;
  s.damping_torque = 0.5;
  EXPECT_EQ(rotation_step(state, 0.5, s, 0.01), 0.0);
  EXPECT_EQ(rotation_step(state, -0.49, s, 0.01), 0.0);
  EXPECT_EQ(angular_acceleration(0.3, 0.5, state.inertia), 0.0);
  EXPECT_EQ(state.angle_rad, 0.0);
}

TEST(NucleusRotation, AngleIsHalfAlphaDtSquaredWithDampingOpposingTheTorque) {
  NucleusRotation state = make_rotation(grid_centres(), 0.5);
  RotationSettings s;
  s.damping_torque = 0.5;
  const double dt = 1.0 / 120, inertia = state.inertia;
  const double alpha = (2.0 - 0.5) / inertia;
  EXPECT_EQ(angular_acceleration(2.0, 0.5, inertia), alpha);
  EXPECT_EQ(rotation_step(state, 2.0, s, dt), 0.5 * alpha * dt * dt);
  EXPECT_EQ(rotation_step(state, -2.0, s, dt), -0.5 * alpha * dt * dt);  // T_d opposes T
  EXPECT_EQ(state.angle_rad, 0.0);
  // Quasi-static: the same torque twice turns twice as far, no carried angular velocity.
  rotation_step(state, 2.0, s, dt);
  rotation_step(state, 2.0, s, dt);
  EXPECT_DOUBLE_EQ(state.angle_rad, alpha * dt * dt);
  // A lighter nucleus (tets removed) turns further under the same torque.
  NucleusRotation light = make_rotation(grid_centres(), 0.5);
  const std::vector<Vec3> gone = {Vec3(3, 2, 0), Vec3(-3, -2, 0)};
  remove_tets(light, gone);
  EXPECT_GT(rotation_step(light, 2.0, s, dt), 0.5 * alpha * dt * dt);
}

TEST(NucleusRotation, RotationKeepsDistanceToTheAxisAndTurnsByTheta) {
  std::vector<float> x = {2.0f, -1.0f, 0.5f, 0.0f}, y = {0.0f, 3.0f, -0.25f, 0.0f},
                     z = {1.0f, -2.0f, 0.3f, 4.0f};
  const auto x0 = x, y0 = y, z0 = z;
  const double theta = 0.3;
  rotate_about_axis(x, y, z, Axis{}, theta);
  for (size_t i = 0; i < x.size(); ++i) {
    EXPECT_NEAR(std::hypot(x[i], y[i]), std::hypot(x0[i], y0[i]), 1e-6);
    EXPECT_EQ(z[i], z0[i]);
  }
  EXPECT_NEAR(std::atan2(y[0], x[0]), theta, 1e-6);  // counter-clockwise seen from +z
  EXPECT_NEAR(std::atan2(y[1], x[1]) - std::atan2(y0[1], x0[1]), theta, 1e-6);

  // A tilted, offset axis with double points.
  const Axis tilted{Vec3(0.5, -0.2, 0.1), Vec3(0.2, 0.1, 1.0).normalized()};
  std::vector<Vec3> pts = {Vec3(1, 2, 3), Vec3(-2, 0.5, -1), Vec3(0.3, 0.3, 0.3)};
  const auto before = pts;
  rotate_about_axis(pts, tilted, -1.1);
  for (size_t i = 0; i < pts.size(); ++i) {
    EXPECT_NEAR(axis_distance2(pts[i], tilted), axis_distance2(before[i], tilted), 1e-12);
    EXPECT_NEAR((pts[i] - tilted.point).dot(tilted.direction),
                (before[i] - tilted.point).dot(tilted.direction), 1e-12);
    EXPECT_GT((pts[i] - before[i]).norm(), 0.1);
  }
}

TEST(NucleusRotation, SameForOneAndFourThreads) {
  std::vector<float> x(50000), y(50000), z(50000);
  for (size_t i = 0; i < x.size(); ++i) x[i] = 0.001f * i, y[i] = 1.0f - 0.00002f * i, z[i] = 0.5f;
  auto x4 = x, y4 = y, z4 = z;
  std::vector<Vec3> centres;
  for (size_t i = 0; i < x.size(); ++i) centres.emplace_back(x[i], y[i], z[i]);
  NucleusRotation s1, s4;
  tbb::task_arena(1).execute([&] {
    rotate_about_axis(x, y, z, Axis{}, 0.01);
    s1 = make_rotation(centres, 1e-9);
  });
  tbb::task_arena(4).execute([&] {
    rotate_about_axis(x4, y4, z4, Axis{}, 0.01);
    s4 = make_rotation(centres, 1e-9);
  });
  EXPECT_EQ(x, x4);
  EXPECT_EQ(y, y4);
  EXPECT_EQ(s1.inertia0, s4.inertia0);
}

}  // namespace
}  // namespace phaco::nucleus
