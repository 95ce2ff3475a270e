// Environment constraints (seed 002 §6): cornea and the two capsule caps as spheres; exact
// projection, inelastic velocity removal, contact flags.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "systems/lens_tools/constraints.hpp"
#include "tests/systems/lens_tools/cell_fixture.hpp"

namespace phaco::lens_tools {
namespace {

// The standard eye (DESIGN.md §6): lens equator radius 4.7, poles +1.8 / −2.7; posterior cornea
// apex 4.8, radius 6.5.
EyeBounds standard(double rhexis = 0, CapFit fit = CapFit::ContainsLens) {
  return eye_bounds(4.7, 1.8, -2.7, 4.8, 6.5, rhexis, fit);
}

// Points on the lens's surface (two half-ellipsoids), in the plane y = 0 (the bag is round).
std::vector<Vec3> lens_outline() {
  std::vector<Vec3> pts;
  for (int k = 0; k <= 400; ++k) {
    const double t = M_PI * k / 400;  // 0 .. π from +x over the top to −x
    pts.emplace_back(4.7 * std::cos(t), 0, 1.8 * std::sin(t));
    pts.emplace_back(4.7 * std::cos(t), 0, -2.7 * std::sin(t));
  }
  return pts;
}

TEST(Constraints, ThroughEquatorCapsPassThroughPoleAndEquatorAndCutTheShoulders) {
  const EyeBounds b = standard(0, CapFit::ThroughEquator);
  for (const auto& [ball, pole] :
       {std::pair{b.anterior_capsule, 1.8}, std::pair{b.posterior_capsule, -2.7}}) {
    EXPECT_NEAR((Vec3(0, 0, pole) - ball.centre).norm(), ball.radius_mm, 1e-12);
    EXPECT_NEAR((Vec3(4.7, 0, 0) - ball.centre).norm(), ball.radius_mm, 1e-12);
    EXPECT_NEAR((Vec3(0, -4.7, 0) - ball.centre).norm(), ball.radius_mm, 1e-12);
  }
  EXPECT_NEAR(b.cornea.centre.z() + b.cornea.radius_mm, 4.8, 1e-12);
  EXPECT_TRUE(inside_bounds(Vec3(0, 0, 1.79), b, 0));
  EXPECT_FALSE(inside_bounds(Vec3(0, 0, 1.81), b, 0));
  EXPECT_FALSE(inside_bounds(Vec3(0, 0, -2.71), b, 0));
  EXPECT_FALSE(inside_bounds(Vec3(4.71, 0, 0), b, 0));
  // The documented shoulder overhang: how far the lens surface sticks out of each cap.
  double out_anterior = 0, out_posterior = 0;
  for (const Vec3& p : lens_outline()) {
    const Ball& cap = p.z() >= 0 ? b.anterior_capsule : b.posterior_capsule;
    const double out = (p - cap.centre).norm() - cap.radius_mm;
    (p.z() >= 0 ? out_anterior : out_posterior) =
        std::max(out, p.z() >= 0 ? out_anterior : out_posterior);
  }
  EXPECT_NEAR(out_anterior, 0.33, 0.01);
  EXPECT_NEAR(out_posterior, 0.33, 0.01);
}

TEST(Constraints, ContainsLensCapsHoldTheWholeLensTouchingAtThePoles) {
  const EyeBounds b = standard();
  for (const Vec3& p : lens_outline()) EXPECT_TRUE(inside_bounds(p, b, 1e-9)) << p.transpose();
  EXPECT_FALSE(inside_bounds(Vec3(0, 0, 1.8 + 1e-6), b, 0));
  EXPECT_FALSE(inside_bounds(Vec3(0, 0, -2.7 - 1e-6), b, 0));
  // The rim where the caps meet: the documented equatorial slack.
  const Vec3 rim = project_into(Vec3(20, 0, 0), b.anterior_capsule, b.posterior_capsule, 0);
  EXPECT_NEAR(rim.x(), 6.2, 0.1);
  EXPECT_NEAR((rim - b.anterior_capsule.centre).norm(), b.anterior_capsule.radius_mm, 1e-9);
  EXPECT_NEAR((rim - b.posterior_capsule.centre).norm(), b.posterior_capsule.radius_mm, 1e-9);
  // A lens at rest is not in contact: constrain leaves it alone.
  LensCells c;
  c.resize(2 * 401);
  const auto pts = lens_outline();
  for (uint32_t i = 0; i < c.size(); ++i) {
    const Vec3 p = pts[i] * (1 - 1e-4);
    c.x[i] = float(p.x()), c.y[i] = float(p.y()), c.z[i] = float(p.z());
  }
  const LensCells before = c;
  constrain(cell_spans(c), b, c.contact);
  EXPECT_EQ(c.x, before.x);
  EXPECT_EQ(c.z, before.z);
  EXPECT_EQ(std::count(c.contact.begin(), c.contact.end(), 1), 0);
}

TEST(Constraints, EveryCellInsideAfterARandomPushAndOutwardVelocityRemoved) {
  LensCells c = test::box_cells(30000, Vec3(-7, -7, -5), Vec3(7, 7, 6), 5);
  const CounterRng rng(5, 2);
  for (uint32_t i = 0; i < c.size(); ++i) {
    c.vx[i] = static_cast<float>(rng.uniform(0, i, 0) * 20 - 10);
    c.vy[i] = static_cast<float>(rng.uniform(0, i, 1) * 20 - 10);
    c.vz[i] = static_cast<float>(rng.uniform(0, i, 2) * 20 - 10);
  }
  const LensCells before = c;
  const EyeBounds b = standard();
  constrain(cell_spans(c), b, c.contact);
  uint32_t moved = 0;
  for (uint32_t i = 0; i < c.size(); ++i) {
    const Vec3 p0(before.x[i], before.y[i], before.z[i]), p(c.x[i], c.y[i], c.z[i]);
    ASSERT_TRUE(inside_bounds(p, b, 0)) << i;
    if (inside_bounds(p0, b, 0)) {
      EXPECT_EQ(c.contact[i], 0) << i;
      EXPECT_EQ(p, p0);
      EXPECT_EQ(c.vx[i], before.vx[i]);
      continue;
    }
    ++moved;
    EXPECT_EQ(c.contact[i], 1) << i;
    EXPECT_LT((p - project_into(p0, b.anterior_capsule, b.posterior_capsule, 0)).norm(), 1e-4);
    if ((p0 - p).norm() < 0.01) continue;  // the normal from float positions is too rough
    const Vec3 n = (p0 - p).normalized();
    const Vec3 v(c.vx[i], c.vy[i], c.vz[i]), v0(before.vx[i], before.vy[i], before.vz[i]);
    EXPECT_LE(v.dot(n), 1e-3) << i;
    // The tangential part is kept.
    EXPECT_LT(((v - v.dot(n) * n) - (v0 - v0.dot(n) * n)).norm(), 1e-3) << i;
  }
  EXPECT_GT(moved, 10000u);
}

TEST(Constraints, ProjectionIsTheNearestAllowedPoint) {
  // Brute force: no point of a dense sample of the bag is closer than the projection.
  for (CapFit fit : {CapFit::ContainsLens, CapFit::ThroughEquator}) {
    const EyeBounds b = standard(0, fit);
    const Ball& ant = b.anterior_capsule;
    const Ball& post = b.posterior_capsule;
    std::vector<Vec3> bag;
    for (double x = -7; x <= 7; x += 0.05)
      for (double z = -3; z <= 2; z += 0.05) {
        const Vec3 p(x, 0, z);
        if (inside_bounds(p, b, 0)) bag.push_back(p);
      }
    // The rim, which the grid misses (the bag is a thin wedge there).
    const Vec3 rim = project_into(Vec3(20, 0, 0), ant, post, 0);
    bag.push_back(rim);
    bag.push_back(Vec3(-rim.x(), 0, rim.z()));
    // Outside points in the plane y = 0: beyond the rim, above and below each pole, off the caps.
    const Vec3 probes[] = {Vec3(9, 0, 0.1), Vec3(8, 0, -0.5), Vec3(7.5, 0, 0),   Vec3(0, 0, 3),
                           Vec3(0, 0, -4),  Vec3(3, 0, 2),    Vec3(-4, 0, -2.5), Vec3(-9, 0, 1)};
    int on_rim = 0;
    for (const Vec3& p : probes) {
      const Vec3 q = project_into(p, ant, post, 0);
      EXPECT_TRUE(inside_bounds(q, b, 1e-9));
      double best = 1e9;
      for (const Vec3& s : bag) best = std::min(best, (p - s).norm());
      EXPECT_LE((p - q).norm(), best + 1e-9) << p.transpose();
      EXPECT_GT((p - q).norm(), best - 0.05) << p.transpose();  // the grid's spacing
      on_rim += std::abs((q - ant.centre).norm() - ant.radius_mm) < 1e-9 &&
                std::abs((q - post.centre).norm() - post.radius_mm) < 1e-9;
    }
    EXPECT_GE(on_rim, 2);  // the rim case was exercised
  }
}

TEST(Constraints, RhexisLetsCellsThroughTheOpeningUnderTheCornea) {
  LensCells c = test::box_cells(3, Vec3::Zero(), Vec3::Zero());
  c.z = {2.5f, 6.0f, 2.5f};
  c.x = {0.0f, 0.0f, 4.0f};
  c.vz = {1.0f, 1.0f, 1.0f};
  constrain(cell_spans(c), standard(2.6), c.contact);
  EXPECT_EQ(c.z[0], 2.5f);  // in the opening, below the cornea: free
  EXPECT_EQ(c.contact[0], 0);
  EXPECT_NEAR(c.z[1], 4.8, 1e-4);  // held by the cornea
  EXPECT_EQ(c.vz[1], 0.0f);
  EXPECT_EQ(c.contact[1], 1);
  EXPECT_TRUE(
      inside_bounds(Vec3(c.x[2], c.y[2], c.z[2]), standard(0), 0));  // outside the opening: bag
  EXPECT_EQ(c.contact[2], 1);

  LensCells closed = test::box_cells(1, Vec3(0, 0, 2.5), Vec3(0, 0, 2.5));
  constrain(cell_spans(closed), standard(0), closed.contact);
  EXPECT_NEAR(closed.z[0], 1.8, 1e-4);
}

TEST(Constraints, SameResultForOneTwoFourThreads) {
  auto run = [](int threads) {
    LensCells c = test::box_cells(20000, Vec3(-7, -7, -5), Vec3(7, 7, 6), 8);
    test::with_threads(threads, [&] { constrain(cell_spans(c), standard(2.5), c.contact); });
    return c;
  };
  const LensCells one = run(1);
  for (int t : {2, 4}) {
    const LensCells other = run(t);
    EXPECT_EQ(one.x, other.x);
    EXPECT_EQ(one.z, other.z);
    EXPECT_EQ(one.contact, other.contact);
  }
}

}  // namespace
}  // namespace phaco::lens_tools
