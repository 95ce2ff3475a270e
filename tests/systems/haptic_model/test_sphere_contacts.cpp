// Lens material as contact spheres in the haptic local model (systems/haptic_model/
// sphere_contacts, issue 19 item 5): one sphere against the exact series-spring reference, a slab
// of spheres felt as one surface along its normal, zero force out of contact, the ultrasound cut
// bound, the god-object keeping the proxy out, and force continuity (≤ 5 % of the range between
// ticks) as the tip slides over a trench edge, presses the trench wall, and sculpts its way
// through material that the "simulation" removes under it.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <memory>

#include "systems/haptic_model/haptic_model.hpp"

namespace phaco::haptic_model {
namespace {

constexpr double kTip = 0.45;   // the phaco tip's radius, mm
constexpr double kCell = 0.15;  // sphere radius, mm (a level-3 lens tet's equal-volume radius)
constexpr double kGap = 0.2;    // centre spacing, mm (overlapping, as neighbouring tets' spheres)

std::unique_ptr<HapticTool> tool_at(const Vec3& tip) {
  auto t = std::make_unique<HapticTool>();
  t->present = true;
  t->tip_radius_mm = float(kTip);
  t->tip_mm = {float(tip.x()), float(tip.y()), float(tip.z())};
  return t;
}

void add_sphere(HapticTool& t, const Vec3& c, double r = kCell, double k = 100) {
  const uint32_t j = t.sphere_count++;
  t.sphere_x[j] = float(c.x()), t.sphere_y[j] = float(c.y()), t.sphere_z[j] = float(c.z());
  t.sphere_r[j] = float(r), t.sphere_k[j] = float(k);
}

// Nucleus material as the publisher sends it: a slab of cells with centres on a grid, top layer
// at z = 0 (its surface z = kCell), for |x|, |y| ≤ half and z ≥ −depth, except where `removed`
// says (a trench, or what the ultrasound took). Nearest to `near` first, at most the capacity.
std::unique_ptr<HapticTool> slab(const Vec3& near, double half, double depth,
                                 const std::function<bool(const Vec3&)>& removed = nullptr) {
  auto t = tool_at(near + Vec3(0, 0, 1));
  std::vector<std::pair<double, Vec3>> cells;
  const int n = int(std::lround(half / kGap));
  for (int i = -n; i <= n; ++i)
    for (int j = -n; j <= n; ++j)
      for (int l = 0; l * kGap <= depth + 1e-9; ++l) {
        const Vec3 c(i * kGap, j * kGap, -l * kGap);
        if (removed && removed(c)) continue;
        if ((c - near).norm() > 1.6) continue;  // the publisher's reach around the tip
        cells.emplace_back((c - near).norm(), c);
      }
  std::sort(cells.begin(), cells.end(),
            [](const auto& a, const auto& b) { return a.first < b.first; });
  for (size_t k = 0; k < cells.size() && t->sphere_count < kHapticMaxSpheres; ++k)
    add_sphere(*t, cells[k].second);
  return t;
}

std::unique_ptr<HapticToolState> fresh_contact_state(const HapticTool& model,
                                                     const HapticSettings& s) {
  auto st = std::make_unique<HapticToolState>();
  adopt_model(model, *st, s);
  return st;
}

// Ticks to let the proxy settle on a held device position.
HapticForce hold(const HapticTool& m, const Vec3& d, const HapticSettings& s, HapticToolState& st,
                 int ticks = 5) {
  HapticForce f;
  for (int k = 0; k < ticks; ++k) f = haptic_tick(m, d, Vec3::Zero(), s, st);
  return f;
}

TEST(SphereContacts, OneSphereIsASpringInSeriesWithTheCoupling) {
  HapticSettings s;
  const Vec3 c(0.3, -0.2, 0.1);
  auto t = tool_at(c + Vec3(0, 0, 2));
  add_sphere(*t, c, 0.2, 150);
  auto st = fresh_contact_state(*t, s);
  const double kser = s.coupling_stiffness_mn_per_mm * 150 / (s.coupling_stiffness_mn_per_mm + 150);
  const Vec3 dir = Vec3(0.3, 0.4, 1).normalized();
  // Approach along dir (the proxy comes from outside, as a hand does), then hold at each depth.
  for (double pen : {0.01, 0.05, 0.2}) {
    for (int k = 0; k <= 20; ++k)
      haptic_tick(*t, c + (0.65 + 1.0 - k * 1.0 / 20) * dir, Vec3::Zero(), s, *st);
    const HapticForce f = hold(*t, c + (0.65 - pen) * dir, s, *st, 20);
    EXPECT_NEAR(f.force_mn.norm(), kser * pen, 1e-6 * kser) << pen;
    EXPECT_GT(f.force_mn.normalized().dot(dir), 1 - 1e-9) << "along the line of centres";
    EXPECT_NEAR(f.sphere_depth_mm, pen, 1e-6);  // centres stored as float
    EXPECT_TRUE(f.active & kTermSpheres);
  }
  const HapticForce out = hold(*t, c + 0.66 * dir, s, *st);
  EXPECT_EQ(out.force_mn.norm(), 0.0) << "out of contact";
  EXPECT_EQ(out.active & kTermSpheres, 0);
}

TEST(SphereContacts, ASlabOfSpheresIsFeltAsOneSurfaceAlongItsNormal) {
  HapticSettings s;
  const double kser = s.coupling_stiffness_mn_per_mm * 100 / (s.coupling_stiffness_mn_per_mm + 100);
  double last = 0;
  for (const Vec3 xy : {Vec3(0, 0, 0), Vec3(0.1, 0, 0), Vec3(0.1, 0.1, 0), Vec3(0.037, 0.071, 0)}) {
    auto t = slab(xy, 1.6, 0.6);
    auto st = fresh_contact_state(*t, s);
    hold(*t, xy + Vec3(0, 0, 1.0), s, *st);
    double prev = 0;
    for (double z = 0.62; z >= 0.3; z -= 0.02) {
      const HapticForce f = hold(*t, xy + Vec3(0, 0, z), s, *st, 3);
      ASSERT_TRUE(std::isfinite(f.force_mn.norm()));
      EXPECT_GE(f.force_mn.z(), prev - 1e-9) << "grows with the press";
      prev = f.force_mn.z();
      // Along the slab's normal: over a cell centre, an edge or a corner by symmetry; anywhere
      // within 9° (the bumps of the cells).
      const bool symmetric = xy.x() == 0.0 || xy.x() == 0.1;
      EXPECT_LE(std::hypot(f.force_mn.x(), f.force_mn.y()),
                (symmetric ? 1e-6 : 0.15) * f.force_mn.norm() + 1e-9);
    }
    // Pressed 0.2 mm below the envelope's top (z = kCell + kTip = 0.6): the stiffness of one
    // surface, k (not the number of spheres touched times k), in series with k_c, on the
    // pen-weighted mean depth of the cells touched (≈ 0.55 of the deepest here).
    const HapticForce f = hold(*t, xy + Vec3(0, 0, 0.4), s, *st, 3);
    EXPECT_GT(f.force_mn.z(), 0.4 * kser * 0.2);
    EXPECT_LT(f.force_mn.z(), 1.05 * kser * 0.2);
    last = f.force_mn.z();
  }
  EXPECT_GT(last, 0);
}

TEST(SphereContacts, TheProxyStaysOutWhenTheDeviceGoesThroughTheMaterial) {
  HapticSettings s;
  s.coupling_stiffness_mn_per_mm = 200;
  auto t = slab(Vec3::Zero(), 1.6, 0.6);
  auto st = fresh_contact_state(*t, s);
  hold(*t, Vec3(0.05, 0.02, 1.0), s, *st);
  // A jump 1.2 mm down in one tick, below the top cells' centres: the material (k = 100, soft
  // next to k_c) lets the proxy in, but keeps pushing it out, up, with the stiffness of the
  // series k_c·k/(k_c + k) on the depths of the cells the tip presses (0.2–0.8 mm here).
  const double kser = 200.0 * 100 / 300;
  for (double z : {0.4, 0.2, 0.0, -0.2}) {
    const HapticForce f = hold(*t, Vec3(0.05, 0.02, z), s, *st, 10);
    EXPECT_GT(f.force_mn.z(), 0.4 * kser * (0.6 - z)) << z;
    EXPECT_LT(f.force_mn.z(), kser * (0.6 - z)) << z;
    EXPECT_LT(std::hypot(f.force_mn.x(), f.force_mn.y()), 0.1 * f.force_mn.z()) << z;
  }
  const HapticForce jumped = hold(*t, Vec3(0.05, 0.02, 1.0), s, *st, 3);
  EXPECT_EQ(jumped.force_mn.norm(), 0.0);
  hold(*t, Vec3(0.05, 0.02, 1.0), s, *st);
  const HapticForce f = hold(*t, Vec3(0.05, 0.02, -0.2), s, *st, 1);
  EXPECT_GT(f.force_mn.z(), 0.4 * kser * 0.8) << "in one tick, still pushed out";
}

TEST(SphereContacts, UnderUltrasoundTheMaterialYieldsAtTheCutForce) {
  HapticSettings s;
  auto t = slab(Vec3::Zero(), 1.6, 0.6);
  auto stiff = fresh_contact_state(*t, s);
  hold(*t, Vec3(0, 0, 1.0), s, *stiff);
  const HapticForce pressed = hold(*t, Vec3(0, 0, 0.2), s, *stiff, 10);
  const double kser = s.coupling_stiffness_mn_per_mm * 100 / (s.coupling_stiffness_mn_per_mm + 100);
  EXPECT_GT(pressed.force_mn.z(), 0.4 * kser * 0.4) << "without ultrasound the nucleus is stiff";
  EXPECT_EQ(pressed.active & kTermCut, 0);

  t->cut_force_mn = 12.0f;
  auto cut = fresh_contact_state(*t, s);
  hold(*t, Vec3(0, 0, 1.0), s, *cut);
  for (double z : {0.55, 0.4, 0.2, 0.0}) {
    const HapticForce f = hold(*t, Vec3(0, 0, z), s, *cut, 10);
    EXPECT_LE(f.force_mn.norm(), 12.0 * (1 + 1e-6)) << z;
    if (z <= 0.4) {
      // Each cell yields at its share of the cut force; the shallow ones at the rim of the
      // contact are still below theirs, so the sum approaches the bound from below.
      EXPECT_GT(f.force_mn.z(), 0.7 * 12.0) << "the reaction approaches the cut force";
      EXPECT_LT(f.force_mn.z(), pressed.force_mn.z()) << "well below the uncut reaction";
      EXPECT_TRUE(f.active & kTermCut);
    }
  }
}

// The device presses onto the nucleus, slides across a trench's edge and falls silent over the
// trench, goes down to its floor, slides into the far wall and is pushed back by it, climbs out
// and slides on. Models (the same geometry, as the simulation republishes it) arrive at 120 Hz.
TEST(SphereContacts, ForceIsContinuousAcrossATrenchEdgeAndItsWall) {
  HapticSettings s;
  s.blend_max_step_mn = 0.25;            // as the capsule's continuity test (test_haptic_model.cpp)
  const double w = 0.7, floor_z = -0.6;  // trench |x| < w, floor cells at z = −0.6 and below
  auto trench = [&](const Vec3& c) { return std::abs(c.x()) < w && c.z() > floor_z + 1e-9; };
  const double surface = kCell + kTip;  // tip centre on the slab's top
  struct Key {
    double t;
    Vec3 p;
  };
  const std::vector<Key> path = {{0.0, {-2.0, 0.03, surface + 0.5}},
                                 {0.2, {-2.0, 0.03, surface - 0.08}},
                                 {0.6, {-0.2, 0.03, surface - 0.08}},            // over the edge
                                 {0.9, {-0.2, 0.03, floor_z + surface - 0.08}},  // on the floor
                                 {1.3, {0.45, 0.03, floor_z + surface - 0.08}},  // into the wall
                                 {1.6, {0.45, 0.03, surface + 0.3}},             // up the wall
                                 {2.0, {1.6, 0.03, surface - 0.08}}};            // and on
  auto device = [&](double t) {
    for (size_t k = 1; k < path.size(); ++k) {
      if (t <= path[k].t) {
        const double a = (t - path[k - 1].t) / (path[k].t - path[k - 1].t);
        return Vec3((1 - a) * path[k - 1].p + a * path[k].p);
      }
    }
    return path.back().p;
  };
  std::unique_ptr<HapticToolState> st;
  std::unique_ptr<HapticTool> model;
  double fmax = 0, jump = 0, wall_push = 0, floor_push = 0;
  Vec3 last = Vec3::Zero();
  for (int k = 0; k <= 2000; ++k) {
    const double t = k * s.dt_s;
    const Vec3 d = device(t);
    if (k % 8 == 0) {  // the simulation's frame: material near the tip, republished
      model = slab(d, 2.4, 1.4, trench);
      if (!st) st = std::make_unique<HapticToolState>();
      adopt_model(*model, *st, s);
    }
    const HapticForce f = haptic_tick(*model, d, Vec3::Zero(), s, *st);
    ASSERT_TRUE(std::isfinite(f.force_mn.norm())) << t;
    if (k > 0) jump = std::max(jump, (f.force_mn - last).norm());
    last = f.force_mn;
    fmax = std::max(fmax, f.force_mn.norm());
    if (std::abs(t - 0.75) < 0.05) {
      EXPECT_EQ(f.force_mn.norm(), 0.0) << "over the trench";
    }
    if (std::abs(t - 0.95) < 0.01) floor_push = f.force_mn.z();
    if (std::abs(t - 1.3) < 0.01) wall_push = f.force_mn.x();
  }
  EXPECT_GT(fmax, 5.0);
  EXPECT_GT(floor_push, 1.0) << "the floor holds the tip up";
  EXPECT_LT(wall_push, -5.0) << "the far wall pushes the tip back";
  EXPECT_LE(jump / fmax, 0.05) << "jump " << jump << " of range " << fmax;
}

// Sculpting through: ultrasound on, the device advances 0.3 mm below the surface; every frame
// (120 Hz) the "simulation" removes the cells whose centres the sculpting sphere reached
// (seed 000 §5.3's centre test, radius 0.45) and republishes. The reaction stays at or below the
// cut force and continuous.
TEST(SphereContacts, SculptingThroughTheNucleusIsContinuousAndBounded) {
  HapticSettings s;
  s.blend_max_step_mn = 0.25;  // as the capsule's continuity test (test_haptic_model.cpp)
  const double cut = 15.0;
  std::vector<Vec3> sculpted;  // device positions at the frames so far
  auto removed = [&](const Vec3& c) {
    for (const Vec3& p : sculpted)
      if ((c - p).norm() <= kTip) return true;
    return false;
  };
  std::unique_ptr<HapticToolState> st;
  std::unique_ptr<HapticTool> model;
  double fmax = 0, jump = 0, mean_x = 0;
  int n_mean = 0;
  Vec3 last = Vec3::Zero();
  const double z = kCell + kTip - 0.3;
  for (int k = 0; k <= 1500; ++k) {
    const double t = k * s.dt_s;
    const Vec3 d(-1.0 + std::max(0.0, t - 0.2) * 1.5, 0.0, t < 0.2 ? 1.0 - (1.0 - z) * t / 0.2 : z);
    if (k % 8 == 0) {
      if (t >= 0.2) sculpted.push_back(d);
      model = slab(d, 2.4, 1.0, removed);
      model->cut_force_mn = float(cut);
      if (!st) st = std::make_unique<HapticToolState>();
      adopt_model(*model, *st, s);
    }
    const HapticForce f = haptic_tick(*model, d, Vec3::Zero(), s, *st);
    ASSERT_TRUE(std::isfinite(f.force_mn.norm()));
    EXPECT_LE(f.force_mn.norm(), cut * (1 + 1e-6) + 1e-9) << t;
    if (k > 0) jump = std::max(jump, (f.force_mn - last).norm());
    last = f.force_mn;
    fmax = std::max(fmax, f.force_mn.norm());
    if (t > 0.4) mean_x += f.force_mn.x(), ++n_mean;
  }
  EXPECT_GT(fmax, 0.5 * cut) << "the material resists the cut";
  EXPECT_LT(mean_x / n_mean, 0.0) << "against the direction of the stroke";
  EXPECT_LE(jump / fmax, 0.05) << "jump " << jump << " of range " << fmax;
}

}  // namespace
}  // namespace phaco::haptic_model
