// Aspirator, hook, gravity and viscosity on lens cells (seed 002 §6).
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>

#include "engine/io/tool_shape.hpp"
#include "systems/lens_tools/cell_dynamics.hpp"
#include "tests/systems/lens_tools/cell_fixture.hpp"

namespace phaco::lens_tools {
namespace {

LensCells cloud(uint32_t n) {
  return test::box_cells(n, Vec3(-2, -2, -2), Vec3(2, 2, 2));
}

double dist(const LensCells& c, uint32_t i, const Vec3& p) {
  return (Vec3(c.x[i], c.y[i], c.z[i]) - p).norm();
}

TEST(Aspirator, PullsCellsInsideTheSphereTowardThePortAndLeavesOthers) {
  LensCells c = cloud(20000);
  const LensCells before = c;
  Aspirator a{Vec3(0.3, 0.1, 0.5), 300.0};
  AspiratorSettings s;
  s.radius_mm = 1.2;
  const double dt = 1.0 / 120;
  aspirate(cell_spans(c), a, s, dt);
  Medium still;
  still.gravity.setZero();
  still.viscosity_per_s = 0;
  integrate(cell_spans(c), still, dt);
  uint32_t pulled = 0;
  for (uint32_t i = 0; i < c.size(); ++i) {
    const double d0 = dist(before, i, a.port);
    if (d0 >= s.radius_mm) {
      EXPECT_EQ(c.vx[i], 0.0f);
      EXPECT_EQ(c.vy[i], 0.0f);
      EXPECT_EQ(c.vz[i], 0.0f);
      continue;
    }
    const Vec3 v(c.vx[i], c.vy[i], c.vz[i]);
    const Vec3 to_port = a.port - Vec3(before.x[i], before.y[i], before.z[i]);
    EXPECT_GT(v.dot(to_port), 0.0) << i;
    // Parallel to the pull, at most d0/dt: the cell gets closer and never passes the port.
    EXPECT_LT(dist(c, i, a.port), d0 + 1e-6) << i;
    EXPECT_LE(v.norm() * dt, d0 * (1 + 1e-5)) << i;
    ++pulled;
  }
  EXPECT_GT(pulled, 300u);
}

TEST(Aspirator, NoVacuumNoPull) {
  LensCells c = cloud(2000);
  aspirate(cell_spans(c), Aspirator{Vec3::Zero(), 0.0}, AspiratorSettings{}, 1.0 / 120);
  for (uint32_t i = 0; i < c.size(); ++i)
    EXPECT_EQ(c.vx[i] * c.vx[i] + c.vy[i] * c.vy[i] + c.vz[i] * c.vz[i], 0.0f);
}

TEST(Hook, DragsCellsInsideTheCylinderOnly) {
  LensCells c = cloud(20000);
  Hook h;
  h.a = h.bend = Vec3(-0.5, 0, 0);  // straight
  h.b = Vec3(0.5, 0.2, 0.3);
  h.velocity = Vec3(0, 40, -10);
  HookSettings s;
  s.radius_mm = 0.4;
  const double dt = 1.0 / 120;
  drag_with_hook(cell_spans(c), h, s, dt);
  const float beta = static_cast<float>(1.0 - std::exp(-s.drag_rate_per_s * dt));
  uint32_t dragged = 0;
  for (uint32_t i = 0; i < c.size(); ++i) {
    const double d = distance_to_segment(Vec3(c.x[i], c.y[i], c.z[i]), h.a, h.b);
    if (d > s.radius_mm + 1e-5) {
      EXPECT_EQ(c.vy[i], 0.0f) << i;
    } else if (d < s.radius_mm - 1e-5) {
      EXPECT_EQ(c.vx[i], 0.0f);
      EXPECT_FLOAT_EQ(c.vy[i], beta * 40.0f);
      EXPECT_FLOAT_EQ(c.vz[i], beta * -10.0f);
      ++dragged;
    }
  }
  EXPECT_GT(dragged, 50u);
  // Beyond the segment's ends (on the line, within the radius of the line) nothing moves.
  LensCells end = test::box_cells(1, Vec3(1.5, 0.4, 0.6), Vec3(1.5, 0.4, 0.6));
  drag_with_hook(cell_spans(end), h, s, dt);
  EXPECT_EQ(end.vy[0], 0.0f);
}

TEST(Hook, BlendDoesNotDependOnHowTheFrameIsSplit) {
  LensCells one = test::box_cells(1, Vec3::Zero(), Vec3::Zero()), two = one;
  Hook h;
  h.a = h.bend = Vec3(-1, 0, 0), h.b = Vec3(1, 0, 0), h.velocity = Vec3(10, 0, 0);
  HookSettings s;
  drag_with_hook(cell_spans(one), h, s, 0.01);
  drag_with_hook(cell_spans(two), h, s, 0.005);
  drag_with_hook(cell_spans(two), h, s, 0.005);
  EXPECT_NEAR(one.vx[0], two.vx[0], 1e-5);
  EXPECT_NEAR(one.vx[0], 10 * (1 - std::exp(-s.drag_rate_per_s * 0.01)), 1e-5);
}

TEST(Hook, FromPosesVelocityAndShaft) {
  ToolPose prev, now;
  prev.pos = Vec3(0, 0, 2);
  now.pos = Vec3(0.1, 0, 2);
  now.quat = Quat(Eigen::AngleAxisd(M_PI / 2, Vec3::UnitY()));  // shaft +z → +x, bend +y stays
  HookSettings s;
  s.shaft_length_mm = 2.0;
  const Hook h = hook_from_poses(now, prev, 0.01, s);
  EXPECT_NEAR((h.velocity - Vec3(10, 0, 0)).norm(), 0, 1e-9);
  EXPECT_NEAR((h.a - now.pos).norm(), 0, 1e-12);
  // The bent end: 1 mm along the instrument's −y from the shaft to the tip (tool_shape.hpp).
  EXPECT_NEAR((h.bend - Vec3(0.1, 1, 2)).norm(), 0, 1e-12);
  EXPECT_NEAR((h.b - Vec3(2.1, 1, 2)).norm(), 0, 1e-12);
}

// The hook drags what the drawn instrument passes through: its bent end and its shaft, which runs
// 1 mm beside the tip (engine/io/tool_shape.hpp, as the rim press and the ports use), not a line
// from the tip along the shaft's direction.
TEST(Hook, DragsAlongTheBentEndAndTheShaftNotTheTipLine) {
  const Quat q(Eigen::AngleAxisd(0.4, Vec3(1, 0.3, 0).normalized()));
  ToolPose now;
  now.pos = Vec3(0.2, -0.1, 0.5);
  now.quat = q;
  HookSettings s;  // radius 0.3 mm, shaft 1 mm
  const Hook h = hook_from_poses(now, now, 0.01, s);
  const Vec3 axis_point = shaft_axis(now, ToolKind::Hook).point;
  const Vec3 up = q * Vec3::UnitZ();
  LensCells c = test::box_cells(1, Vec3::Zero(), Vec3::Zero());
  const auto dragged = [&](const Vec3& p) {
    LensCells one = c;
    one.x[0] = static_cast<float>(p.x()), one.y[0] = static_cast<float>(p.y());
    one.z[0] = static_cast<float>(p.z());
    Hook moving = h;
    moving.velocity = Vec3(0, 0, 10);
    drag_with_hook(cell_spans(one), moving, s, 0.01);
    return one.vz[0] != 0.0f;
  };
  EXPECT_TRUE(dragged(0.5 * (now.pos + axis_point)));  // the middle of the bent end
  EXPECT_TRUE(dragged(axis_point + 0.6 * up));         // on the shaft above the bend
  EXPECT_FALSE(dragged(now.pos + 0.6 * up));           // the tip line: no instrument there
  EXPECT_FALSE(dragged(now.pos + 0.6 * up + 0.1 * (q * Vec3::UnitX())));
}

TEST(Euler, FreeFallIsHalfGTSquaredToFirstOrder) {
  const double g = 892.0, t_end = 0.25;
  double previous_error = 0;
  for (int steps : {60, 120, 240}) {
    LensCells c = test::box_cells(1, Vec3(0, 0, 1), Vec3(0, 0, 1));
    Medium m;
    m.gravity = Vec3(0, 0, -g);
    m.viscosity_per_s = 0;
    const double dt = t_end / steps;
    for (int k = 0; k < steps; ++k) integrate(cell_spans(c), m, dt);
    const double fall = 1.0 - c.z[0];
    // Semi-implicit Euler exactly: Σ_{k=1..n} k g dt² = ½ g t² + ½ g t dt.
    EXPECT_NEAR(fall, 0.5 * g * dt * dt * steps * (steps + 1), 1e-4 * fall);
    const double error = fall - 0.5 * g * t_end * t_end;
    EXPECT_GT(error, 0);
    EXPECT_LT(error, g * t_end * dt);
    if (previous_error > 0) {
      EXPECT_NEAR(error / previous_error, 0.5, 0.01);
    }
    previous_error = error;
  }
}

TEST(Euler, ViscosityDecaysVelocityByTheDiscreteFactor) {
  LensCells c = test::box_cells(1, Vec3::Zero(), Vec3::Zero());
  c.vx[0] = 5.0f, c.vy[0] = -3.0f;
  Medium m;
  m.gravity.setZero();
  m.viscosity_per_s = 6.0;
  const double dt = 1.0 / 120;
  float vx = 5.0f, vy = -3.0f, x = c.x[0];
  const float fdt = static_cast<float>(dt), fc = 6.0f;
  for (int k = 0; k < 60; ++k) {
    integrate(cell_spans(c), m, dt);
    vx += fdt * (0.0f - fc * vx);  // the same float operations the system does
    vy += fdt * (0.0f - fc * vy);
    x += fdt * vx;
  }
  EXPECT_EQ(c.vx[0], vx);
  EXPECT_EQ(c.vy[0], vy);
  EXPECT_EQ(c.x[0], x);
  EXPECT_NEAR(c.vx[0], 5.0 * std::pow(1 - 6.0 * dt, 60), 1e-5);
  // (1 − c dt)^n → e^{−c t} as dt → 0; at c dt = 0.05 within 10 % after t = 0.5 s, and below it.
  const double decay = c.vx[0] / 5.0, exact = std::exp(-6.0 * 0.5);
  EXPECT_LT(decay, exact);
  EXPECT_NEAR(decay / exact, 1.0, 0.1);
}

TEST(CellDynamics, DeadCellsStayPut) {
  LensCells c = cloud(500);
  std::fill(c.alive.begin(), c.alive.end(), uint8_t{0});
  const LensCells before = c;
  aspirate(cell_spans(c), Aspirator{Vec3::Zero(), 500}, AspiratorSettings{}, 0.01);
  Hook h;
  h.velocity = Vec3(3, 3, 3);
  drag_with_hook(cell_spans(c), h, HookSettings{}, 0.01);
  integrate(cell_spans(c), Medium{}, 0.01);
  EXPECT_EQ(c.x, before.x);
  EXPECT_EQ(c.vz, before.vz);
}

TEST(CellDynamics, SameStateForOneTwoFourThreads) {
  auto frame_run = [](int threads) {
    LensCells c = cloud(30000);
    test::with_threads(threads, [&] {
      for (int f = 0; f < 5; ++f) {
        aspirate(cell_spans(c), Aspirator{Vec3(0.5, 0, 0), 400}, AspiratorSettings{}, 0.01);
        Hook h;
        h.a = Vec3(-1, -1, 0), h.bend = Vec3(-1, -0.5, 0), h.b = Vec3(1, 1, 0);
        h.velocity = Vec3(0, 0, 20);
        drag_with_hook(cell_spans(c), h, HookSettings{}, 0.01);
        integrate(cell_spans(c), Medium{}, 0.01);
      }
    });
    return c;
  };
  const LensCells one = frame_run(1);
  for (int t : {2, 4}) {
    const LensCells other = frame_run(t);
    EXPECT_EQ(std::memcmp(one.x.data(), other.x.data(), one.x.size() * sizeof(float)), 0) << t;
    EXPECT_EQ(std::memcmp(one.vz.data(), other.vz.data(), one.vz.size() * sizeof(float)), 0) << t;
  }
}

}  // namespace
}  // namespace phaco::lens_tools
