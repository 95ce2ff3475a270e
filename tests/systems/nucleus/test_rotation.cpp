// Nucleus rotation about the optical axis (seed 000 §5.4; the push a kinematic contact, issue 19).
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
  EXPECT_EQ(contact_rotation_step(s, 0.1, 1, 0.01), 0.0);
}

// The bag's friction and damping (systems/nucleus/rotation.hpp, step 1).
TEST(NucleusRotation, TheBagDampsAndStopsAFreeNucleusWithoutTurningItBack) {
  NucleusRotation state = make_rotation(grid_centres(), 0.5);
  const double inertia = state.inertia, dt = 1.0 / 120;
  RotationSettings s;
  s.friction_torque = 0;
  s.damping = inertia;  // c Δt / I = Δt: ω decays by 1 / (1 + Δt) a step (implicit)
  state.angular_velocity = 2.0;
  EXPECT_DOUBLE_EQ(free_rotation_step(state, s, dt), 2.0 / (1 + dt) * dt);
  EXPECT_DOUBLE_EQ(state.angular_velocity, 2.0 / (1 + dt));
  // Coulomb friction alone: ω falls by T_f Δt / I a step, then sticks at zero.
  s.damping = 0;
  s.friction_torque = 0.5 * state.angular_velocity * inertia / dt;  // stops it in two steps
  const double w0 = state.angular_velocity;
  free_rotation_step(state, s, dt);
  EXPECT_NEAR(state.angular_velocity, 0.5 * w0, 1e-12);
  free_rotation_step(state, s, dt);
  EXPECT_NEAR(state.angular_velocity, 0.0, 1e-12);
  const double stopped = state.angle_rad;
  EXPECT_EQ(free_rotation_step(state, s, dt), 0.0) << "friction never turns it back";
  EXPECT_EQ(state.angle_rad, stopped);
  // A stiff viscous bag (c Δt / I ≫ 1, the standard eye) stops it within a step.
  state.angular_velocity = 1.0;
  s = RotationSettings{0.0, 1000 * inertia / dt};
  free_rotation_step(state, s, dt);
  EXPECT_LT(std::abs(state.angular_velocity), 1e-3);
  // Nothing left to turn.
  remove_tets(state, grid_centres());
  state.angular_velocity = 1.0;
  EXPECT_EQ(free_rotation_step(state, RotationSettings{}, dt), 0.0);
  EXPECT_EQ(state.angular_velocity, 0.0);
}

// The wall cannot pass the tip (step 2): after the clearance turn, the nearest wall point is on
// the tip's sphere, exactly.
TEST(NucleusRotation, ClearanceTurnPutsTheWallOnTheTipsSphere) {
  const Vec3 tip(2.0, 0.0, 0.5);
  const double r = 0.45;
  // A point on the tip's circle about the axis, 0.1 rad ahead (counter-clockwise): inside the
  // sphere (chord 0.2 mm). It must end where the chord is r: ψ = 2 asin(r / (2ρ)).
  const std::vector<Vec3> one = {Vec3(2 * std::cos(0.1), 2 * std::sin(0.1), 0.5)};
  const double psi_max = 2 * std::asin(r / 4.0);
  EXPECT_NEAR(wall_clearance_angle(one, tip, r, +1), psi_max - 0.1, 1e-12);
  EXPECT_EQ(wall_clearance_angle(one, tip, r, -1), 0.0) << "behind a clockwise push";
  std::vector<Vec3> turned = one;
  rotate_about_axis(turned, Axis{}, psi_max - 0.1);
  EXPECT_NEAR((turned[0] - tip).norm(), r, 1e-12);
  // Mirrored: the same point below the x axis asks the same clockwise.
  const std::vector<Vec3> mirrored = {Vec3(one[0].x(), -one[0].y(), 0.5)};
  EXPECT_NEAR(wall_clearance_angle(mirrored, tip, r, -1), psi_max - 0.1, 1e-12);
  // Off the tip's circle (other radius and height): the turn still ends on the sphere.
  const std::vector<Vec3> off = {Vec3(2.2, 0.15, 0.3), Vec3(1.9, 0.05, 0.7), Vec3(2.0, 0.6, 0.5),
                                 Vec3(2.0, -0.1, 0.5)};  // the last two: outside, behind
  const double turn = wall_clearance_angle(off, tip, r, +1);
  ASSERT_GT(turn, 0.0);
  std::vector<Vec3> inside(off.begin(), off.begin() + 2);
  rotate_about_axis(inside, Axis{}, turn);
  EXPECT_NEAR(std::min((inside[0] - tip).norm(), (inside[1] - tip).norm()), r, 1e-9);
  EXPECT_GE(std::max((inside[0] - tip).norm(), (inside[1] - tip).norm()), r - 1e-9);
  // Points outside the sphere ask nothing; a tip on the axis cannot push.
  const std::vector<Vec3> outside = {Vec3(2.0, 0.6, 0.5), Vec3(2.0, 0.0, 1.5)};
  EXPECT_EQ(wall_clearance_angle(outside, tip, r, +1), 0.0);
  EXPECT_EQ(wall_clearance_angle(one, Vec3(0, 0, 0.5), r, +1), 0.0);
}

TEST(NucleusRotation, ContactTurnSetsTheAngularVelocityAndTheWallsTorque) {
  NucleusRotation state = make_rotation(grid_centres(), 0.5);
  const double dt = 1.0 / 120;
  const double torque = contact_rotation_step(state, 0.01, -1, dt);
  EXPECT_DOUBLE_EQ(state.angle_rad, -0.01);
  EXPECT_DOUBLE_EQ(state.angular_velocity, -0.01 / dt);
  EXPECT_DOUBLE_EQ(torque, state.inertia * 0.01 / (dt * dt));
  EXPECT_DOUBLE_EQ(state.contact_torque_max, torque);
  EXPECT_EQ(contact_rotation_step(state, 0.0, 1, dt), 0.0);
  EXPECT_EQ(contact_rotation_step(state, 0.01, 0, dt), 0.0);
  EXPECT_DOUBLE_EQ(state.angle_rad, -0.01);
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
