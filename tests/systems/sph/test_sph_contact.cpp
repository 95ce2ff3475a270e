// Fragment contact and environment constraints (systems/sph/contact.hpp, environment.hpp).
#include <gtest/gtest.h>
#include <oneapi/tbb/task_arena.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <random>
#include <vector>

#include "systems/sph/contact.hpp"
#include "systems/sph/environment.hpp"

namespace phaco::sph {
namespace {

constexpr CellOrder kOrders[] = {CellOrder::Morton, CellOrder::Linear, CellOrder::UnsortedHash};

// Lens-like numbers: cells 0.1 mm apart, support 0.15 mm, 1.1e-9 kg per cell (1.1 mg/mm³).
constexpr float kSpacing = 0.1f;
constexpr float kH = 0.15f;
constexpr float kCellMass = 1.1e-9f;

struct Bodies {
  std::vector<float> x, y, z, vx, vy, vz;
  std::vector<uint32_t> fragment;
  std::vector<uint8_t> boundary;
  uint32_t size() const { return static_cast<uint32_t>(x.size()); }
  void add(float px, float py, float pz, float ux, float uy, float uz, uint32_t frag,
           uint8_t b = 1) {
    x.push_back(px), y.push_back(py), z.push_back(pz);
    vx.push_back(ux), vy.push_back(uy), vz.push_back(uz);
    fragment.push_back(frag), boundary.push_back(b);
  }
  ContactParticles view() const { return {x, y, z, vx, vy, vz, fragment, boundary}; }
};

struct Forces {
  std::vector<float> x, y, z;
  explicit Forces(uint32_t n) : x(n, 0.0f), y(n, 0.0f), z(n, 0.0f) {}
};

// Two interleaved blobs of two fragments with random velocities.
Bodies interleaved(uint32_t n, uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(0.0f, 1.0f), v(-20.0f, 20.0f);
  Bodies b;
  for (uint32_t i = 0; i < n; ++i)
    b.add(u(rng), u(rng), 0.5f * u(rng), v(rng), v(rng), v(rng), i % 3 == 0 ? 0u : 1u, i % 5 != 0);
  return b;
}

TEST(SphContact, PairForceIsExactlyAntisymmetric) {
  ContactParams p;
  p.h = kH, p.stiffness = 2.0f, p.damping = 1e-4f;
  Bodies b;
  b.add(0.01f, 0.02f, 0.03f, 5.0f, -1.0f, 0.5f, 0);
  b.add(0.09f, 0.05f, -0.02f, -3.0f, 2.0f, 0.0f, 1);
  for (CellOrder order : kOrders) {
    p.order = order;
    Forces f(2);
    ContactScratch s;
    const ContactStats st = fragment_contact(b.view(), 2, p, s, f.x, f.y, f.z);
    EXPECT_EQ(st.pairs, 1u);
    EXPECT_GT(std::abs(f.x[0]), 0.0f);
    EXPECT_EQ(f.x[0], -f.x[1]);
    EXPECT_EQ(f.y[0], -f.y[1]);
    EXPECT_EQ(f.z[0], -f.z[1]);
    EXPECT_LT(f.x[0], 0.0f) << "particle 0 is pushed away from 1 (toward −x)";
  }
}

TEST(SphContact, ForceShapeRisesToThePeakAndNeverAttracts) {
  ContactParams p;
  p.h = kH, p.stiffness = 1.0f, p.damping = 1e-3f;
  float prev = 0.0f;
  for (int k = 99; k >= 1; --k) {  // r from h inward
    const float r = kH * static_cast<float>(k) / 100.0f;
    const float f = pair_force_scale(p, r * r, 0.0f) * r;
    EXPECT_GE(f, prev * (1.0f - 1e-5f)) << "monotone in penetration, r = " << r;
    EXPECT_LE(f, p.stiffness * p.h * (1.0f + 1e-5f));
    prev = f;
  }
  EXPECT_NEAR(pair_force_scale(p, 0.01f * kH * kH, 0.0f) * 0.1f * kH, p.stiffness * p.h, 1e-6f);
  EXPECT_EQ(pair_force_scale(p, kH * kH, 0.0f), 0.0f);
  EXPECT_EQ(pair_force_scale(p, 0.0f, 0.0f), 0.0f);
  // Separating fast: damping would pull, clamped to no force.
  const float r = 0.5f * kH;
  EXPECT_EQ(pair_force_scale(p, r * r, 1e6f * r), 0.0f);
  EXPECT_GT(pair_force_scale(p, r * r, -10.0f * r), pair_force_scale(p, r * r, 0.0f));
}

TEST(SphContact, SameFragmentAndInteriorCellsExertNothing) {
  Bodies b = interleaved(600, 3);
  ContactParams p;
  p.h = kH;
  std::fill(b.fragment.begin(), b.fragment.end(), 7u);
  for (CellOrder order : kOrders) {
    p.order = order;
    Forces f(b.size());
    ContactScratch s;
    const ContactStats st = fragment_contact(b.view(), 2, p, s, f.x, f.y, f.z);
    EXPECT_GT(st.particles, 0u);
    EXPECT_EQ(st.pairs, 0u);
    for (uint32_t i = 0; i < b.size(); ++i) ASSERT_EQ(f.x[i], 0.0f);
  }
  // Two fragments: interior (non-boundary) cells get no force and do not push others.
  b = interleaved(600, 3);
  Forces f(b.size());
  ContactScratch s;
  const ContactStats st = fragment_contact(b.view(), 2, p, s, f.x, f.y, f.z);
  EXPECT_GT(st.pairs, 100u);
  Bodies only_boundary;
  std::vector<uint32_t> keep;
  for (uint32_t i = 0; i < b.size(); ++i) {
    if (!b.boundary[i]) {
      EXPECT_EQ(f.x[i], 0.0f);
      EXPECT_EQ(f.y[i], 0.0f);
      EXPECT_EQ(f.z[i], 0.0f);
      continue;
    }
    keep.push_back(i);
    only_boundary.add(b.x[i], b.y[i], b.z[i], b.vx[i], b.vy[i], b.vz[i], b.fragment[i]);
  }
  Forces g(only_boundary.size());
  fragment_contact(only_boundary.view(), 2, p, s, g.x, g.y, g.z);
  for (uint32_t k = 0; k < keep.size(); ++k) EXPECT_EQ(g.x[k], f.x[keep[k]]);
}

TEST(SphContact, FewerThanTwoFragmentsDoNoWork) {
  Bodies b = interleaved(100, 4);
  Forces f(b.size());
  std::fill(f.x.begin(), f.x.end(), 3.0f);
  ContactScratch s;
  const ContactStats st = fragment_contact(b.view(), 1, ContactParams{}, s, f.x, f.y, f.z);
  EXPECT_EQ(st.particles, 0u);
  EXPECT_EQ(s.grid.count, 0u) << "no grid was built";
  for (float v : f.x) EXPECT_EQ(v, 3.0f);
}

TEST(SphContact, MomentumIsConservedInFreeFlight) {
  // Free cells, two fragments interleaved; symplectic Euler in double (the integrator is the
  // test's), forces from the system.
  Bodies b = interleaved(1500, 8);
  const uint32_t n = b.size();
  ContactParams p;
  p.h = kH, p.stiffness = 1e-5f, p.damping = 1e-9f;
  const double dt = 2e-5;
  std::vector<double> X(n), Y(n), Z(n), VX(n), VY(n), VZ(n);
  for (uint32_t i = 0; i < n; ++i)
    X[i] = b.x[i], Y[i] = b.y[i], Z[i] = b.z[i], VX[i] = b.vx[i], VY[i] = b.vy[i], VZ[i] = b.vz[i];
  auto momentum = [&](int axis) {
    double s = 0.0;
    for (uint32_t i = 0; i < n; ++i)
      s += kCellMass * (axis == 0 ? VX[i] : axis == 1 ? VY[i] : VZ[i]);
    return s;
  };
  double scale = 0.0;  // the largest Σ m|v| seen
  auto measure = [&] {
    double sum = 0.0;
    for (uint32_t i = 0; i < n; ++i)
      sum += kCellMass * std::sqrt(VX[i] * VX[i] + VY[i] * VY[i] + VZ[i] * VZ[i]);
    scale = std::max(scale, sum);
  };
  measure();
  const double p0[3] = {momentum(0), momentum(1), momentum(2)};
  ContactScratch s;
  double impulse = 0.0;  // Σ |f| dt: how much the forces did
  for (int step = 0; step < 200; ++step) {
    for (uint32_t i = 0; i < n; ++i) {
      b.x[i] = float(X[i]), b.y[i] = float(Y[i]), b.z[i] = float(Z[i]);
      b.vx[i] = float(VX[i]), b.vy[i] = float(VY[i]), b.vz[i] = float(VZ[i]);
    }
    Forces f(n);
    fragment_contact(b.view(), 2, p, s, f.x, f.y, f.z);
    for (uint32_t i = 0; i < n; ++i) {
      impulse +=
          std::sqrt(double(f.x[i]) * f.x[i] + double(f.y[i]) * f.y[i] + double(f.z[i]) * f.z[i]) *
          dt;
      VX[i] += f.x[i] / kCellMass * dt, VY[i] += f.y[i] / kCellMass * dt,
          VZ[i] += f.z[i] / kCellMass * dt;
      X[i] += VX[i] * dt, Y[i] += VY[i] * dt, Z[i] += VZ[i] * dt;
    }
    measure();
  }
  EXPECT_GT(impulse, 0.05 * scale) << "the contacts must change the velocities noticeably";
  for (int a = 0; a < 3; ++a)
    EXPECT_LE(std::abs(momentum(a) - p0[a]), 1e-6 * scale) << "axis " << a;
}

// Two 5×5×5 cubes (rigid: each fragment moves as one body, as shape matching would make it)
// driven into each other; returns the smallest inter-fragment distance and the final velocities.
struct Collision {
  double min_distance = 1e9, v_left = 0.0, v_right = 0.0, momentum_error = 0.0, momentum = 0.0;
};
Collision collide(float speed, float damping) {
  Bodies b;
  const int n = 5;
  const float gap = kH + 0.02f;  // faces start just outside the support
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j)
      for (int k = 0; k < n; ++k) {
        b.add(-gap / 2 - kSpacing * i, kSpacing * j, kSpacing * k, speed, 0, 0, 0, i == 0);
        // The right cube is shifted half a spacing in y and z: faces do not meet head-on.
        b.add(gap / 2 + kSpacing * i, kSpacing * (j + 0.5f), kSpacing * (k + 0.5f), -speed, 0, 0, 1,
              i == 0);
      }
  const double mass = kCellMass * n * n * n;  // per fragment
  const double front_mass = mass / (n * n);   // what each front cell has to stop
  ContactParams p;
  p.h = kH, p.damping = damping;
  p.stiffness = stiffness_to_stop(2.0f * speed, static_cast<float>(front_mass / 2), kH, 0.5f);
  const double dt = 2e-5;
  double v[2] = {speed, -speed}, offset[2] = {0.0, 0.0};
  std::vector<float> x0 = b.x;
  std::vector<uint32_t> front[2];
  for (uint32_t i = 0; i < b.size(); ++i)
    if (b.boundary[i]) front[b.fragment[i]].push_back(i);
  ContactScratch s;
  Collision c;
  c.momentum = mass * 2 * speed;
  for (int step = 0; step < 2000; ++step) {
    for (uint32_t i = 0; i < b.size(); ++i) {
      b.x[i] = x0[i] + float(offset[b.fragment[i]]);
      b.vx[i] = float(v[b.fragment[i]]);
    }
    for (uint32_t i : front[0])
      for (uint32_t j : front[1]) {
        const double dx = b.x[i] - b.x[j], dy = b.y[i] - b.y[j], dz = b.z[i] - b.z[j];
        c.min_distance = std::min(c.min_distance, std::sqrt(dx * dx + dy * dy + dz * dz));
      }
    Forces f(b.size());
    fragment_contact(b.view(), 2, p, s, f.x, f.y, f.z);
    double force[2] = {0.0, 0.0};
    for (uint32_t i = 0; i < b.size(); ++i) force[b.fragment[i]] += f.x[i];
    c.momentum_error = std::max(c.momentum_error, std::abs(force[0] + force[1]) * dt);
    for (int k = 0; k < 2; ++k) {
      v[k] += force[k] / mass * dt;
      offset[k] += v[k] * dt;
    }
  }
  c.v_left = v[0];
  c.v_right = v[1];
  return c;
}

TEST(SphContact, DrivenFragmentsDoNotInterpenetrate) {
  // Closing speed 2 × 20 mm/s, k from stiffness_to_stop for the mass behind one front cell:
  // no pair of the two fragments comes closer than h/2 and they separate again.
  const Collision elastic = collide(20.0f, 0.0f);
  std::printf("[ info ] elastic: closest %.4f h, rebound %.3f mm/s\n", elastic.min_distance / kH,
              elastic.v_left);
  EXPECT_GE(elastic.min_distance, 0.5 * kH);
  EXPECT_LT(elastic.min_distance, 0.95 * kH) << "they did touch";
  EXPECT_LT(elastic.v_left, 0.0);
  EXPECT_GT(elastic.v_right, 0.0);
  EXPECT_NEAR(elastic.v_left, -elastic.v_right, 1e-4 * 20.0);
  EXPECT_LE(elastic.momentum_error, 1e-6 * elastic.momentum);
  // Damping along the normal takes energy out: slower rebound, still no interpenetration.
  const Collision damped = collide(20.0f, 5e-7f);
  std::printf("[ info ] damped: closest %.4f h, rebound %.3f mm/s\n", damped.min_distance / kH,
              damped.v_left);
  EXPECT_GE(damped.min_distance, 0.5 * kH);
  EXPECT_LT(std::abs(damped.v_left), std::abs(elastic.v_left));
  EXPECT_LE(damped.momentum_error, 1e-6 * damped.momentum);
}

TEST(SphContact, OnePairStopsWhereStiffnessToStopSays) {
  for (float stop : {0.3f, 0.5f, 0.8f}) {
    const float speed = 10.0f;  // each, so 20 mm/s closing
    ContactParams p;
    p.h = kH;
    p.stiffness = stiffness_to_stop(2 * speed, kCellMass / 2, kH, stop);
    double x[2] = {-0.51 * kH, 0.51 * kH}, v[2] = {speed, -speed}, closest = 1e9;
    ContactScratch s;
    for (int step = 0; step < 20000; ++step) {
      Bodies b;
      b.add(float(x[0]), 0, 0, float(v[0]), 0, 0, 0);
      b.add(float(x[1]), 0, 0, float(v[1]), 0, 0, 1);
      Forces f(2);
      fragment_contact(b.view(), 2, p, s, f.x, f.y, f.z);
      for (int k = 0; k < 2; ++k) {
        v[k] += f.x[k] / kCellMass * 1e-6;
        x[k] += v[k] * 1e-6;
      }
      closest = std::min(closest, x[1] - x[0]);
    }
    EXPECT_NEAR(closest / kH, stop, 0.01) << "stop fraction " << stop;
  }
}

// Every order's pass (the sorted ones filter eight candidates at a time) against the O(n²) sum
// over all pairs: the same pairs, and each particle's force within float rounding of the
// double-precision sum of the same pair forces. Three fragments, a size that is not a multiple of
// eight, a few coincident pairs (no direction: no force) and non-boundary particles (no part).
TEST(SphContact, EveryOrderFindsThePairsABruteForceSumFinds) {
  Bodies b = interleaved(2999, 31);
  for (uint32_t i = 0; i < b.size(); i += 7) b.fragment[i] = 2;
  for (uint32_t i = 0; i + 1 < 40; i += 2)  // coincident pairs of two fragments
    b.add(b.x[i], b.y[i], b.z[i], 0, 0, 0, b.fragment[i] == 0 ? 1u : 0u);
  ContactParams p;
  p.h = 0.05f, p.stiffness = 2.0f, p.damping = 1e-4f;
  const uint32_t n = b.size();
  std::vector<double> rx(n, 0.0), ry(n, 0.0), rz(n, 0.0);
  uint64_t pairs = 0;
  for (uint32_t i = 0; i < n; ++i) {
    for (uint32_t j = 0; j < n; ++j) {
      if (j == i || !b.boundary[i] || !b.boundary[j] || b.fragment[i] == b.fragment[j]) continue;
      const float dx = b.x[i] - b.x[j], dy = b.y[i] - b.y[j], dz = b.z[i] - b.z[j];
      const float r2 = dx * dx + dy * dy + dz * dz;
      if (!(r2 < p.h * p.h)) continue;
      const float vd =
          (b.vx[i] - b.vx[j]) * dx + (b.vy[i] - b.vy[j]) * dy + (b.vz[i] - b.vz[j]) * dz;
      const float s = pair_force_scale(p, r2, vd);
      rx[i] += s * dx, ry[i] += s * dy, rz[i] += s * dz;
      pairs += i < j;
    }
  }
  double peak = 0;
  for (uint32_t i = 0; i < n; ++i)
    peak = std::max({peak, std::abs(rx[i]), std::abs(ry[i]), std::abs(rz[i])});
  ASSERT_GT(pairs, 500u);
  for (CellOrder order : kOrders) {
    p.order = order;
    Forces f(n);
    ContactScratch scratch;
    const ContactStats st = fragment_contact(b.view(), 3, p, scratch, f.x, f.y, f.z);
    EXPECT_EQ(st.pairs, pairs) << to_string(order);
    double worst = 0;
    for (uint32_t i = 0; i < n; ++i)
      worst = std::max(
          {worst, std::abs(f.x[i] - rx[i]), std::abs(f.y[i] - ry[i]), std::abs(f.z[i] - rz[i])});
    EXPECT_LT(worst, 1e-5 * peak) << to_string(order);
  }
}

TEST(SphContact, ForcesAreBitIdenticalForOneAndTwoThreads) {
  const Bodies b = interleaved(30000, 12);
  ContactParams p;
  p.h = 0.02f, p.stiffness = 1.0f, p.damping = 1e-6f;
  for (CellOrder order : kOrders) {
    p.order = order;
    std::vector<float> out[2];
    ContactStats st[2];
    for (int t = 0; t < 2; ++t) {
      tbb::task_arena arena(t + 1);
      arena.execute([&] {
        Forces f(b.size());
        ContactScratch s;
        st[t] = fragment_contact(b.view(), 2, p, s, f.x, f.y, f.z);
        out[t] = f.x;
        out[t].insert(out[t].end(), f.y.begin(), f.y.end());
        out[t].insert(out[t].end(), f.z.begin(), f.z.end());
      });
    }
    EXPECT_GT(st[0].pairs, 1000u);
    EXPECT_EQ(st[0].pairs, st[1].pairs);
    EXPECT_EQ(0, std::memcmp(out[0].data(), out[1].data(), out[0].size() * sizeof(float)))
        << to_string(order);
  }
}

// A caller's own list of the boundary particles and their box (fragment_lens' mark_boundary) give
// the forces of fragment_contact's own walk and bounds, to the bit, in every order.
TEST(SphContact, GivenMembersAndBoxGiveTheForcesOfTheWalk) {
  const Bodies b = interleaved(6000, 5);
  ContactParams p;
  p.h = 0.03f, p.stiffness = 1.0f, p.damping = 1e-6f;
  std::vector<uint32_t> members;
  std::array<float, 6> box{1e30f, 1e30f, 1e30f, -1e30f, -1e30f, -1e30f};
  for (uint32_t i = 0; i < b.size(); ++i) {
    if (!b.boundary[i]) continue;
    members.push_back(i);
    const float q[3] = {b.x[i], b.y[i], b.z[i]};
    for (int a = 0; a < 3; ++a)
      box[a] = std::min(box[a], q[a]), box[a + 3] = std::max(box[a + 3], q[a]);
  }
  for (CellOrder order : kOrders) {
    p.order = order;
    Forces walked(b.size()), given(b.size());
    ContactScratch s0, s1;
    const ContactStats st0 = fragment_contact(b.view(), 2, p, s0, walked.x, walked.y, walked.z);
    ContactParticles in = b.view();
    in.members = members;
    in.members_box = &box;
    const ContactStats st1 = fragment_contact(in, 2, p, s1, given.x, given.y, given.z);
    EXPECT_GT(st0.pairs, 500u) << to_string(order);
    EXPECT_EQ(st0.pairs, st1.pairs) << to_string(order);
    EXPECT_EQ(s0.members, s1.members) << to_string(order);
    EXPECT_EQ(s0.grid.origin[0], s1.grid.origin[0]) << to_string(order);
    for (const auto& [w, g] :
         {std::pair{&walked.x, &given.x}, {&walked.y, &given.y}, {&walked.z, &given.z}})
      EXPECT_EQ(0, std::memcmp(w->data(), g->data(), w->size() * sizeof(float)))
          << to_string(order);
  }
}

TEST(SphEnvironment, CellsLeavingASphereAreProjectedBackInelasticallyAndFlaggedHeavy) {
  std::vector<float> x = {0.0f, 3.0f, 0.5f, 0.0f}, y = {0.0f, 0.0f, 0.0f, 0.0f},
                     z = {0.0f, 4.0f, 0.0f, 0.0f};
  std::vector<float> vx = {1.0f, 2.0f, 0.0f, 0.0f}, vy = {0.0f, 7.0f, 0.0f, 0.0f},
                     vz = {0.0f, 1.0f, 3.0f, 0.0f};
  std::vector<uint8_t> heavy(4, 9);
  const ConstraintSphere bag{0.0f, 0.0f, 0.0f, 2.5f, true};
  const ConstraintSphere tool{0.5f, 0.0f, 0.2f, 0.5f, false};
  const ConstraintSphere spheres[] = {bag, tool};
  const uint32_t hits = constrain_to_spheres(spheres, {x, y, z, vx, vy, vz}, heavy);
  EXPECT_EQ(hits, 2u);
  // Cell 1 was at radius 5 moving outward: now on the bag (0.6, 0.8)·2.5, outward speed gone,
  // tangential speed kept.
  EXPECT_NEAR(x[1], 1.5f, 1e-6f);
  EXPECT_NEAR(z[1], 2.0f, 1e-6f);
  EXPECT_NEAR(vx[1] * 0.6f + vz[1] * 0.8f, 0.0f, 1e-6f);
  EXPECT_NEAR(vy[1], 7.0f, 1e-6f);
  EXPECT_NEAR(vx[1] * 0.8f - vz[1] * 0.6f, 2.0f * 0.8f - 1.0f * 0.6f, 1e-5f);
  EXPECT_EQ(heavy[1], 1);
  // Cell 2 was inside the tool's bulb moving into it: pushed out along −z to its surface.
  EXPECT_NEAR(z[2], 0.2f - 0.5f, 1e-6f);
  EXPECT_NEAR(vz[2], 0.0f, 1e-6f);
  EXPECT_EQ(heavy[2], 1);
  // Cells 0 and 3 were allowed: untouched, not heavy.
  EXPECT_EQ(x[0], 0.0f);
  EXPECT_EQ(vx[0], 1.0f);
  EXPECT_EQ(heavy[0], 0);
  EXPECT_EQ(heavy[3], 0);
  EXPECT_EQ(heavy_weight(2.0f, heavy[1]), 2.0f * kHeavyMassFactor);
  EXPECT_EQ(heavy_weight(2.0f, heavy[0]), 2.0f);
}

}  // namespace
}  // namespace phaco::sph
