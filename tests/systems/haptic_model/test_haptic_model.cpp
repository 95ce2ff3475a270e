// The haptic thread's local force model (systems/haptic_model): virtual wall, passivity on both
// sides of Colgate & Schenkel's bound, grasped membrane, lens depth against an analytic reference,
// continuity across model arrivals and a stall, grasp series stiffness, clamp and NaN input, and
// implicit against explicit node integration at the capsule's real mass and stiffness.
#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdlib>
#include <functional>
#include <limits>
#include <memory>
#include <new>
#include <vector>

#include "systems/haptic_model/haptic_model.hpp"

// Counts every allocation in this executable, to show that ticks and adopts make none.
namespace {
std::atomic<uint64_t> g_allocations{0};  // relaxed: a counter read after the work, same thread
}  // namespace
void* operator new(std::size_t n) {
  g_allocations.fetch_add(1, std::memory_order_relaxed);
  if (void* p = std::malloc(n ? n : 1)) return p;
  throw std::bad_alloc();
}
// GCC pairs the malloc above with a `new` it sees inlined at call sites and warns; it is matched.
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wmismatched-new-delete"
void operator delete(void* p) noexcept {
  std::free(p);
}
void operator delete(void* p, std::size_t) noexcept {
  std::free(p);
}
#pragma GCC diagnostic pop

namespace phaco::haptic_model {
namespace {

constexpr double kPi = 3.14159265358979323846;

std::unique_ptr<HapticTool> blank_tool() {
  auto t = std::make_unique<HapticTool>();
  t->present = true;
  t->tip_radius_mm = 0.15f;
  t->tip_mm = {0, 0, 1};
  return t;
}

uint16_t add_node(HapticTool& t, double x, double y, double z, HapticNodeKind kind,
                  double mass = 1e-10) {
  const uint32_t i = t.node_count++;
  t.x[i] = float(x), t.y[i] = float(y), t.z[i] = float(z);
  t.mass[i] = float(mass);
  t.kind[i] = kind;
  return uint16_t(i);
}

void add_spring(HapticTool& t, uint16_t i, uint16_t j, double k, double rest) {
  const uint32_t s = t.spring_count++;
  t.spring_i[s] = i, t.spring_j[s] = j, t.k_mn_per_mm[s] = float(k), t.rest_mm[s] = float(rest);
}

// Virtual wall: two anchored triangles forming the square [-5, 5]² in the plane z = 0.
std::unique_ptr<HapticTool> wall(double patch_stiffness) {
  auto t = blank_tool();
  add_node(*t, -5, -5, 0, HapticNodeKind::Anchored);
  add_node(*t, 5, -5, 0, HapticNodeKind::Anchored);
  add_node(*t, 5, 5, 0, HapticNodeKind::Anchored);
  add_node(*t, -5, 5, 0, HapticNodeKind::Anchored);
  t->triangle_count = 2;
  t->triangles[0] = {0, 1, 2};
  t->triangles[1] = {0, 2, 3};
  t->patch_stiffness_mn_per_mm = float(patch_stiffness);
  return t;
}

// A square membrane of n × n nodes in the plane z = z0, rim anchored, springs along the grid and
// one diagonal per cell, rest lengths shortened by `prestretch` (tension gives it out-of-plane
// stiffness), two triangles per cell.
std::unique_ptr<HapticTool> membrane(int n, double spacing, double k, double prestretch,
                                     double z0 = 0, double damping = 0.1, double mass = 1e-10) {
  auto t = blank_tool();
  const double half = 0.5 * spacing * (n - 1);
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      const bool rim = i == 0 || j == 0 || i == n - 1 || j == n - 1;
      add_node(*t, i * spacing - half, j * spacing - half, z0,
               rim ? HapticNodeKind::Anchored : HapticNodeKind::Free, mass);
    }
  auto id = [n](int i, int j) { return uint16_t(j * n + i); };
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      if (i + 1 < n) add_spring(*t, id(i, j), id(i + 1, j), k, spacing / (1 + prestretch));
      if (j + 1 < n) add_spring(*t, id(i, j), id(i, j + 1), k, spacing / (1 + prestretch));
      if (i + 1 < n && j + 1 < n) {
        add_spring(*t, id(i, j), id(i + 1, j + 1), k, spacing * std::sqrt(2.0) / (1 + prestretch));
        t->triangles[t->triangle_count++] = {id(i, j), id(i + 1, j), id(i + 1, j + 1)};
        t->triangles[t->triangle_count++] = {id(i, j), id(i + 1, j + 1), id(i, j + 1)};
      }
    }
  t->damping_mn_s_per_mm = float(damping);
  t->tip_mm = {0.1f, 0.1f, float(z0 + 1.0)};
  return t;
}

std::unique_ptr<HapticToolState> fresh(const HapticTool& model, const HapticSettings& s) {
  auto st = std::make_unique<HapticToolState>();
  adopt_model(model, *st, s);
  return st;
}

// A device of mass m with physical (hand + mechanism) damping b, pushed by a constant user force,
// its motion integrated finely between samples; the force sampled and held at the haptic rate
// (zero-order hold), the velocity the tick sees a backward difference, as a real device's.
struct DeviceRun {
  std::vector<double> t, e;  // sample times, energy
  std::vector<Vec3> x, v, f;
};
DeviceRun run_device(const HapticTool& model, const HapticSettings& s, double m, double b,
                     const Vec3& user, Vec3 x, Vec3 v, double seconds,
                     const std::function<double(const Vec3&, const Vec3&)>& energy,
                     int substeps = 40) {
  auto st = fresh(model, s);
  DeviceRun run;
  Vec3 prev = x;
  const int ticks = int(seconds / s.dt_s);
  const double h = s.dt_s / substeps;
  for (int k = 0; k < ticks; ++k) {
    const HapticForce hf = haptic_tick(st->newest_model(), x, (x - prev) / s.dt_s, s, *st);
    prev = x;
    run.t.push_back(k * s.dt_s), run.x.push_back(x), run.v.push_back(v),
        run.f.push_back(hf.force_mn);
    run.e.push_back(energy(x, v));
    for (int j = 0; j < substeps; ++j) {  // semi-implicit in the damping: exact decay, no growth
      v = (v + h / m * (hf.force_mn + user)) / (1 + h * b / m);
      x += h * v;
    }
  }
  return run;
}

double max_in(const std::vector<double>& e, size_t from, size_t to) {
  return *std::max_element(e.begin() + from, e.begin() + std::min(to, e.size()));
}

// ---------------------------------------------------------------------------------------------

TEST(HapticModel, VirtualWallForceIsCouplingTimesDepthWhenRigid) {
  HapticSettings s;
  s.coupling_stiffness_mn_per_mm = 800;
  auto w = wall(0.0);  // rigid: k_p = 1000·k_c
  auto st = fresh(*w, s);
  const double r = w->tip_radius_mm;
  const double kser = 800.0 * 800e3 / (800.0 + 800e3);
  for (double depth : {0.02, 0.1, 0.3}) {
    HapticForce f;
    for (int k = 0; k < 3; ++k)
      f = haptic_tick(*w, Vec3(0.3, -1.2, r - depth), Vec3::Zero(), s, *st);
    EXPECT_NEAR(f.force_mn.z(), kser * depth, 1e-6 * kser) << depth;
    EXPECT_NEAR(f.force_mn.x(), 0, 1e-9);
    EXPECT_NEAR(f.force_mn.y(), 0, 1e-9);
    EXPECT_NEAR(f.proxy_mm.z(), r - depth / 1001.0, 1e-9);
    EXPECT_TRUE(f.active & kTermContact);
  }
  // On the shared diagonal both triangles touch: merged, not counted twice.
  const HapticForce diag = haptic_tick(*w, Vec3(1, 1, r - 0.1), Vec3::Zero(), s, *st);
  EXPECT_NEAR(diag.force_mn.z(), kser * 0.1, 1e-6 * kser);
  // Outside: no force.
  const HapticForce out = haptic_tick(*w, Vec3(0.3, -1.2, r + 0.01), Vec3::Zero(), s, *st);
  EXPECT_EQ(out.force_mn.norm(), 0.0);
  EXPECT_EQ(out.active & kTermContact, 0);
}

TEST(HapticModel, VirtualWallSeriesStiffnessWhenSoft) {
  HapticSettings s;
  s.coupling_stiffness_mn_per_mm = 1000;
  auto w = wall(500.0);
  auto st = fresh(*w, s);
  const double r = w->tip_radius_mm;
  const HapticForce f = haptic_tick(*w, Vec3(2, 2.5, r - 0.2), Vec3::Zero(), s, *st);
  EXPECT_NEAR(f.force_mn.z(), 1000.0 * 500.0 / 1500.0 * 0.2, 1e-6);
  EXPECT_NEAR(f.penetration_mm, 1000.0 / 1500.0 * 0.2, 1e-9);
}

TEST(HapticModel, GodObjectDoesNotTunnelThroughTheWall) {
  HapticSettings s;
  s.coupling_stiffness_mn_per_mm = 100;
  auto w = wall(0.0);
  auto st = fresh(*w, s);
  // The device jumps 1.2 mm behind the wall in one tick: the proxy stays on the tool's side.
  haptic_tick(*w, Vec3(0, 0, 0.5), Vec3::Zero(), s, *st);
  const HapticForce f = haptic_tick(*w, Vec3(0, 0, -1.2), Vec3::Zero(), s, *st);
  EXPECT_GT(f.proxy_mm.z(), 0.14);
  EXPECT_NEAR(f.force_mn.z(), 100.0 * (1.35) * 1000.0 / 1001.0, 1e-3);
}

// Colgate & Schenkel (1997): a sampled virtual spring K over a device with physical damping b is
// passive when b > K·T/2 (no virtual damper). Pushed into the wall with a constant force, the
// device oscillates about its rest point: the oscillation's energy dies out below the bound and
// grows above it.
double sustained_growth(double k, double rate_hz, double b) {
  HapticSettings s;
  s.coupling_stiffness_mn_per_mm = k;
  s.dt_s = 1.0 / rate_hz;
  auto w = wall(0.0);
  const double r = w->tip_radius_mm, m = 0.05, push = 300.0;
  const double kser = k * 1000.0 / 1001.0;
  const double z_eq = r - push / kser;
  auto energy = [&](const Vec3& x, const Vec3& v) {
    return 0.5 * m * v.squaredNorm() + 0.5 * kser * (x.z() - z_eq) * (x.z() - z_eq);
  };
  const DeviceRun run = run_device(*w, s, m, b, Vec3(0, 0, -push), Vec3(0, 0, z_eq + 0.02),
                                   Vec3::Zero(), 0.6, energy);
  const size_t n = run.e.size(), win = n / 6;
  return max_in(run.e, n - win, n) / max_in(run.e, 0, win);
}

TEST(HapticModel, WallPassiveBelowColgateBoundAndNotAbove) {
  const double b = 1.0, rate = 1000.0;  // mN·s/mm, Hz: bound 2·b/T = 2000 mN/mm
  const double bound = 2 * b * rate;
  EXPECT_LT(sustained_growth(0.5 * bound, rate, b), 0.1);
  EXPECT_LT(sustained_growth(0.85 * bound, rate, b), 1.0);
  EXPECT_GT(sustained_growth(1.5 * bound, rate, b), 1.0);
  EXPECT_GT(sustained_growth(3.0 * bound, rate, b), 10.0);
  // Halving the rate halves the bound: 1.5·(2b/T at 500 Hz) grows, 0.5·it does not.
  EXPECT_LT(sustained_growth(0.5 * bound / 2, rate / 2, b), 0.1);
  EXPECT_GT(sustained_growth(1.5 * bound / 2, rate / 2, b), 1.0);
}

// A bounce: the device falls onto the wall and leaves it; passive: it leaves with less kinetic
// energy than it came with (less what the hand's damping took); above the bound, with more.
double bounce_gain(double k, double b) {
  HapticSettings s;
  s.coupling_stiffness_mn_per_mm = k;
  auto w = wall(0.0);
  const double m = 0.05, v0 = 100.0;
  auto energy = [&](const Vec3&, const Vec3& v) { return 0.5 * m * v.squaredNorm(); };
  const DeviceRun run =
      run_device(*w, s, m, b, Vec3::Zero(), Vec3(0, 0, 0.3), Vec3(0, 0, -v0), 0.2, energy);
  // The first sample after leaving the wall (contact over, moving up).
  bool touched = false;
  for (size_t k = 0; k < run.f.size(); ++k) {
    if (run.f[k].z() > 0) touched = true;
    if (touched && run.f[k].z() == 0 && run.v[k].z() > 0) return run.e[k] / (0.5 * m * v0 * v0);
  }
  return 0;
}

TEST(HapticModel, WallBounceGainsEnergyOnlyAboveTheBound) {
  const double b = 1.0, bound = 2 * b / 0.001;
  EXPECT_LT(bounce_gain(0.5 * bound, b), 1.0);
  EXPECT_GT(bounce_gain(3.0 * bound, b), 1.0);
}

// The grasped membrane: the device holds the middle node of a small sheet by the coupling, is
// pulled sideways and released; the sheet's springs make the wall here. Its stiffness at the
// grasped node is measured first (static pull), then the run is judged against 2·b/T.
double membrane_stiffness(const HapticTool& model, const HapticSettings& s) {
  auto st = fresh(model, s);
  const Vec3 g(model.x[model.grasped_node], model.y[model.grasped_node],
               model.z[model.grasped_node]);
  HapticForce f;
  for (int k = 0; k < 400; ++k) f = haptic_tick(model, g + Vec3(0.01, 0, 0), Vec3::Zero(), s, *st);
  return -f.force_mn.x() / 0.01;
}

double grasp_growth(double spring_k, double b, double* k_eff) {
  HapticSettings s;
  s.coupling_stiffness_mn_per_mm = 20000;
  auto sheet = membrane(5, 0.5, spring_k, 0.05, 0.0, 0.0);
  sheet->grasped_node = 12;  // the middle of 5 × 5
  sheet->kind[12] = HapticNodeKind::Grasped;
  *k_eff = membrane_stiffness(*sheet, s);
  const double m = 0.05;
  const Vec3 g(sheet->x[12], sheet->y[12], sheet->z[12]);
  auto energy = [&](const Vec3& x, const Vec3& v) {
    return 0.5 * m * v.squaredNorm() + 0.5 * *k_eff * (x - g).squaredNorm();
  };
  const DeviceRun run =
      run_device(*sheet, s, m, b, Vec3::Zero(), g + Vec3(0.05, 0, 0), Vec3::Zero(), 0.6, energy);
  const size_t n = run.e.size(), win = n / 6;
  return max_in(run.e, n - win, n) / max_in(run.e, 0, win);
}

TEST(HapticModel, GraspedMembranePassiveBelowColgateBoundAndNotAbove) {
  const double b = 0.1, bound = 2 * b / 0.001;  // 200 mN/mm
  double k_soft = 0, k_stiff = 0;
  const double soft = grasp_growth(10.0, b, &k_soft);
  const double stiff = grasp_growth(150.0, b, &k_stiff);
  ASSERT_LT(k_soft, 0.7 * bound);
  ASSERT_GT(k_stiff, 1.5 * bound);
  EXPECT_LT(soft, 0.5);
  EXPECT_GT(stiff, 1.0);
}

// Seed 003 §E.5: the lens's penetration depth against points placed on a known normal.
TEST(HapticModel, LensPenetrationDepthMatchesAnalyticReference) {
  auto t = blank_tool();
  t->lens_present = true;
  t->lens_centre_mm = {0.3f, -0.2f, 0.1f};
  const double a = t->lens_equator_radius_mm, c1 = t->lens_anterior_mm, c2 = t->lens_posterior_mm;
  const Vec3 centre(0.3, -0.2, 0.1);
  const double r = 0.15;
  int checked = 0;
  for (double phi : {0.0, 1.1, 2.7}) {
    for (double theta :
         {1.5707963, 1.2, 0.6, 0.02, -0.02, -0.6, -1.2, -1.5707963}) {  // both halves, equator
      const double c = theta >= 0 ? c1 : c2;
      const double rho = a * std::cos(theta), z = c * std::sin(theta);
      Vec3 n2(rho / (a * a), 0, z / (c * c));
      n2.normalize();
      const Vec3 e(std::cos(phi), std::sin(phi), 0);
      const Vec3 q = centre + rho * e + Vec3(0, 0, z);
      const Vec3 n = n2.x() * e + Vec3(0, 0, n2.z());
      for (double depth : {-0.25, -0.05, 0.0, 0.04, 0.2}) {  // depth of the point below the surface
        const LensContact lc = lens_penetration(*t, q - depth * n, r);
        EXPECT_NEAR(lc.depth_mm, r + depth, 1e-6) << theta << " " << depth;
        EXPECT_NEAR(lc.normal.dot(n), 1.0, 1e-6);
        EXPECT_NEAR((lc.nearest_mm - q).norm(), 0.0, 1e-5);
        ++checked;
      }
    }
  }
  EXPECT_EQ(checked, 3 * 8 * 5);
  // Far away: clearly not touching; no lens: never touching.
  EXPECT_LT(lens_penetration(*t, centre + Vec3(0, 0, 10), r).depth_mm, 0);
  t->lens_present = false;
  EXPECT_LT(lens_penetration(*t, centre, r).depth_mm, 0);
}

TEST(HapticModel, LensForceIsSeedPenaltyInSeriesWithCoupling) {
  HapticSettings s;
  s.coupling_stiffness_mn_per_mm = 1000;
  auto t = blank_tool();
  t->lens_present = true;
  t->lens_centre_mm = {0, 0, 0};
  t->lens_stiffness_mn_per_mm = 50;
  t->tip_mm = {0, 0, 3};
  auto st = fresh(*t, s);
  const double r = t->tip_radius_mm, c1 = t->lens_anterior_mm;
  const HapticForce f = haptic_tick(*t, Vec3(0, 0, c1 + r - 0.1), Vec3::Zero(), s, *st);
  const double kser = 1000.0 * 50.0 / 1050.0;
  EXPECT_NEAR(f.force_mn.z(), kser * 0.1, 1e-6);  // F = k_f·d, d the proxy's depth
  EXPECT_NEAR(f.lens_depth_mm, 1000.0 / 1050.0 * 0.1, 1e-7);
  EXPECT_TRUE(f.active & kTermLens);
}

// Grasp: the grasped node held by the coupling, the user feels the springs: one spring, or a chain
// of three in series (analytic: 1/k_eff = 1/k_c + Σ 1/k).
TEST(HapticModel, GraspForceMatchesSeriesStiffness) {
  HapticSettings s;
  s.coupling_stiffness_mn_per_mm = 1000;
  for (int springs : {1, 3}) {
    auto t = blank_tool();
    t->damping_mn_s_per_mm = 0.1f;
    add_node(*t, 0, 0, 0, HapticNodeKind::Anchored);
    for (int i = 1; i <= springs; ++i) {
      add_node(*t, i, 0, 0, i == springs ? HapticNodeKind::Grasped : HapticNodeKind::Free);
      add_spring(*t, uint16_t(i - 1), uint16_t(i), 40.0, 1.0);
    }
    t->grasped_node = uint16_t(springs);
    const double k_eff = 1.0 / (1.0 / 1000.0 + springs / 40.0);
    double last = 0;
    for (double pull : {0.05, 0.1, 0.2}) {
      auto st = fresh(*t, s);
      HapticForce f;
      for (int k = 0; k < 500; ++k)
        f = haptic_tick(*t, Vec3(springs + pull, 0, 0), Vec3::Zero(), s, *st);
      EXPECT_NEAR(f.force_mn.x(), -k_eff * pull, 2e-3 * k_eff * pull) << springs << " " << pull;
      EXPECT_TRUE(f.active & kTermGrasp);
      EXPECT_GT(-f.force_mn.x(), last);  // grows with the pull, toward the membrane
      last = -f.force_mn.x();
    }
  }
}

// Issue 17 item 5: a held flap tears at the capsule's resistance, so the device feels at most that
// (HapticTool::grasp_limit_mn); without a limit the same pull is felt in full.
TEST(HapticModel, GraspForceIsBoundedByTheFlapsTearResistance) {
  HapticSettings s;
  s.coupling_stiffness_mn_per_mm = 1000;
  auto t = blank_tool();
  t->damping_mn_s_per_mm = 0.1f;
  add_node(*t, 0, 0, 0, HapticNodeKind::Anchored);
  add_node(*t, 1, 0, 0, HapticNodeKind::Grasped);
  add_spring(*t, 0, 1, 40.0, 1.0);
  t->grasped_node = 1;
  const double limit = 9.75;  // the standard eye's F_c
  for (double pull : {0.1, 0.5, 2.0}) {
    double free_pull = 0, bounded = 0;
    for (float g : {0.0f, float(limit)}) {
      t->grasp_limit_mn = g;
      auto st = fresh(*t, s);
      HapticForce f;
      for (int k = 0; k < 500; ++k) f = haptic_tick(*t, Vec3(1 + pull, 0, 0), Vec3::Zero(), s, *st);
      (g > 0 ? bounded : free_pull) = f.force_mn.norm();
      EXPECT_LT(f.force_mn.x(), 0.0) << "toward the membrane";
    }
    EXPECT_LE(bounded, limit + 1e-6) << pull;
    EXPECT_NEAR(bounded, std::min(free_pull, limit), 1e-3 * limit) << pull;
    if (pull >= 2.0) {
      EXPECT_GT(free_pull, 2 * limit) << "the pull is well above the plateau";
    }
  }
}

TEST(HapticModel, ForceNeverExceedsTheDeviceMaximum) {
  HapticSettings s;
  s.coupling_stiffness_mn_per_mm = 1000;
  s.max_force_mn = 300;
  auto w = wall(0.0);
  auto st = fresh(*w, s);
  for (double depth = 0; depth < 1.5; depth += 0.05) {
    const HapticForce f = haptic_tick(*w, Vec3(0.2, 0.1, 0.15 - depth), Vec3::Zero(), s, *st);
    EXPECT_LE(f.force_mn.norm(), 300.0 + 1e-9);
    EXPECT_EQ(f.clamped, 1000.0 * depth > 300.0 * 1.0011) << depth;
  }
  EXPECT_GT(st->clamped_ticks, 0u);
}

TEST(HapticModel, NanDeviceInputGivesZeroForceAndDoesNotPoisonTheState) {
  HapticSettings s;
  auto sheet = membrane(7, 0.5, 40, 0.05);
  auto a = fresh(*sheet, s);
  auto b = fresh(*sheet, s);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  for (int k = 0; k < 50; ++k) {
    const Vec3 dev(0.1, 0.05, 0.15 - 0.004 * k);
    const HapticForce fa = haptic_tick(*sheet, dev, Vec3::Zero(), s, *a);
    if (k % 7 == 3) {
      const HapticForce bad = haptic_tick(*sheet, Vec3(nan, 0, 0), Vec3::Zero(), s, *b);
      EXPECT_TRUE(bad.input_rejected);
      EXPECT_EQ(bad.force_mn.norm(), 0.0);
      const HapticForce bad2 =
          haptic_tick(*sheet, dev, Vec3(0, std::numeric_limits<double>::infinity(), 0), s, *b);
      EXPECT_TRUE(bad2.input_rejected);
    }
    const HapticForce fb = haptic_tick(*sheet, dev, Vec3::Zero(), s, *b);
    ASSERT_EQ(fa.force_mn, fb.force_mn) << k;  // the rejected samples changed nothing
  }
  EXPECT_EQ(b->inputs_rejected, 14u);
  EXPECT_GT(a->last_force.z(), 1.0);  // it was pressing
}

TEST(HapticModel, TicksAndAdoptsDoNotAllocate) {
  HapticSettings s;
  auto sheet = membrane(9, 0.5, 40, 0.05);
  auto grasped = membrane(9, 0.5, 40, 0.05);
  grasped->grasped_node = 40;
  grasped->kind[40] = HapticNodeKind::Grasped;
  grasped->lens_present = true;
  grasped->lens_stiffness_mn_per_mm = 20;
  grasped->lens_centre_mm = {0, 0, -2};
  // Lens material below the sheet and a held fragment (issue 19 item 5) on the same path.
  for (int i = 0; i < 64; ++i) {
    const uint32_t j = sheet->sphere_count++;
    sheet->sphere_x[j] = float(0.2 * (i % 8) - 0.7),
    sheet->sphere_y[j] = float(0.2 * (i / 8) - 0.7);
    sheet->sphere_z[j] = -0.3f, sheet->sphere_r[j] = 0.15f, sheet->sphere_k[j] = 100.0f;
  }
  sheet->cut_force_mn = 20.0f;
  sheet->held = {.held = true,
                 .mass_kg = 4e-5f,
                 .drag_mn_s_per_mm = 0.1f,
                 .weight_mn = {0, 0, -0.03f},
                 .hold_limit_mn = 11.0f};
  // Both through a corneal port (issue 20 item 2), levered against it.
  for (HapticTool* t : {sheet.get(), grasped.get()}) {
    t->port_present = true;
    t->port_centre_mm = {4.0f, 0.0f, 2.0f};
    t->port_axis = {-1.0f, 0.0f, 0.0f};
    t->port_width_dir = {0.0f, 1.0f, 0.0f};
    t->port_half_width_mm = 1.2f, t->port_tunnel_length_mm = 1.75f;
    t->port_stiffness_mn_per_mm = 200.0f;
  }
  auto st = fresh(*sheet, s);
  const uint64_t before = g_allocations.load(std::memory_order_relaxed);
  uint8_t terms = 0;
  for (int k = 0; k < 300; ++k) {
    if (k % 30 == 0) adopt_model(k % 60 ? *grasped : *sheet, *st, s);
    terms |= haptic_tick(st->newest_model(), Vec3(0.1, 0.1, 0.1 - 0.001 * k), Vec3::Zero(),
                         Vec3(1.0, 0.0, 0.5), s, *st)
                 .active;
  }
  EXPECT_TRUE(terms & kTermPort);
  EXPECT_EQ(g_allocations.load(std::memory_order_relaxed), before);
  EXPECT_EQ(st->models_adopted, 11u);
}

// At the capsule's real node mass (1e-10 kg) and spring stiffness (40 mN/mm) ω·dt ≈ 600 at 1 ms:
// symplectic Euler explodes within a few ticks; backward Euler stays bounded and near rest.
TEST(HapticModel, ExplicitIntegrationBlowsUpWhereImplicitStaysBounded) {
  auto sheet = membrane(7, 0.5, 40, 0.05);
  auto run = [&](NodeIntegrator integrator, double* max_disp) {
    HapticSettings s;
    s.integrator = integrator;
    auto st = fresh(*sheet, s);
    *max_disp = 0;
    for (int k = 0; k < 40; ++k) {
      haptic_tick(*sheet, Vec3(0.1, 0.05, 0.15 - 0.005 * k), Vec3::Zero(), s, *st);
      const HapticSlot& slot = st->slot[st->newest];
      for (uint32_t i = 0; i < sheet->node_count; ++i) {
        const double d =
            std::sqrt(std::pow(slot.x[i] - sheet->x[i], 2) + std::pow(slot.y[i] - sheet->y[i], 2) +
                      std::pow(slot.z[i] - sheet->z[i], 2));
        *max_disp = std::max(*max_disp, std::isfinite(d) ? d : 1e300);
      }
    }
    return st->slot_resets;
  };
  double explicit_disp = 0, implicit_disp = 0;
  const uint64_t explicit_resets = run(NodeIntegrator::SymplecticEuler, &explicit_disp);
  const uint64_t implicit_resets = run(NodeIntegrator::ImplicitEuler, &implicit_disp);
  EXPECT_TRUE(explicit_resets > 0 || explicit_disp > 10.0) << explicit_disp;
  EXPECT_EQ(implicit_resets, 0u);
  EXPECT_LT(implicit_disp, 0.5);  // the tip pressed 0.05 mm past the sheet
  EXPECT_GT(implicit_disp, 0.01);
}

// The membrane gives way under the tool: it is pushed down with the tip, and the force grows with
// the press like the series of the coupling and the sheet's stiffness (softer than the wall).
TEST(HapticModel, MembraneGivesWayUnderTheTool) {
  HapticSettings s;
  auto sheet = membrane(9, 0.5, 40, 0.05);
  auto st = fresh(*sheet, s);
  HapticForce f;
  for (int k = 0; k < 200; ++k)
    f = haptic_tick(*sheet, Vec3(0.1, 0.1, 0.15 - 0.2 * k / 200.0), Vec3::Zero(), s, *st);
  for (int k = 0; k < 100; ++k)
    f = haptic_tick(*sheet, Vec3(0.1, 0.1, -0.05), Vec3::Zero(), s, *st);
  const HapticSlot& slot = st->slot[st->newest];
  const double centre_z = slot.z[4 * 9 + 4];
  EXPECT_LT(centre_z, -0.1);  // moved with the tip
  EXPECT_GT(f.force_mn.z(), 0.5);
  EXPECT_LT(f.force_mn.z(), 1000.0 * 0.2 * 0.5);  // far below the rigid wall's k_c·0.2
  EXPECT_TRUE(f.active & kTermContact);
}

// Continuity: the simulation's membrane rises and falls (its rim with it); its models arrive at
// 30 Hz, with a 200 ms stall in the middle; the device presses and circles. Between two ticks the
// force never jumps by more than 5 % of its range with the crossfade, and does without it.
double continuity_jump(double blend_ms, double blend_max_step, double model_hz, double* range_out) {
  HapticSettings s;
  s.blend_ms = blend_ms;
  s.blend_max_step_mn = blend_max_step;
  std::unique_ptr<HapticToolState> st;
  std::unique_ptr<HapticTool> model;
  auto sim_z = [](double t) { return 0.15 * std::sin(2 * kPi * 1.3 * t); };
  double next_model = 0, fmin = 1e300, fmax = -1e300, jump = 0;
  Vec3 last = Vec3::Zero();
  const double period = 1.0 / model_hz;
  for (int k = 0; k < 1500; ++k) {
    const double t = k * s.dt_s;
    const bool stalled = t > 0.6 && t < 0.8;
    if (t >= next_model && !stalled) {
      // The simulation follows the tool too: it publishes the sheet as the haptic thread has it
      // deformed, moved with its rim (which the haptic model cannot know of until it arrives).
      const double z0 = sim_z(t);
      auto next = membrane(9, 0.5, 40, 0.2, z0);
      if (st) {
        const HapticSlot& now = st->slot[st->newest];
        const double shift = z0 - now.model.z[0];
        for (uint32_t i = 0; i < next->node_count; ++i) {
          next->x[i] = float(now.x[i]), next->y[i] = float(now.y[i]),
          next->z[i] = float(now.z[i] + shift);
        }
      }
      model = std::move(next);
      if (!st) st = std::make_unique<HapticToolState>();
      adopt_model(*model, *st, s);
      next_model += period;
      while (next_model <= t) next_model += period;
    }
    const Vec3 dev(0.6 * std::cos(2 * kPi * 0.7 * t), 0.6 * std::sin(2 * kPi * 0.7 * t),
                   0.3 - 0.55 * std::min(1.0, t / 0.2) - 0.15 * std::sin(2 * kPi * 0.9 * t));
    const HapticForce f = haptic_tick(st->newest_model(), dev, Vec3::Zero(), s, *st);
    EXPECT_TRUE(std::isfinite(f.force_mn.norm()));
    if (k > 0) jump = std::max(jump, (f.force_mn - last).norm());
    last = f.force_mn;
    fmin = std::min(fmin, f.force_mn.z()), fmax = std::max(fmax, f.force_mn.z());
  }
  *range_out = fmax - fmin;
  return jump / (fmax - fmin);
}

TEST(HapticModel, ForceStaysContinuousAcrossModelsAndAStall) {
  double range = 0;
  const double with = continuity_jump(4.0, 0.25, 30.0, &range);
  EXPECT_GT(range, 10.0);
  EXPECT_LE(with, 0.05);
  const double without = continuity_jump(0.0, 0.0, 30.0, &range);
  EXPECT_GT(without, 0.05);
  EXPECT_GT(without, 2 * with);
}

}  // namespace
}  // namespace phaco::haptic_model
