// The fragmenting lens (seed 002 pipeline): asleep until touched; a cut through the lens makes two
// fragments that stay rigid, inside the eye, apart from each other and finite; same result for
// one and two threads.
#include <gtest/gtest.h>
#include <oneapi/tbb/task_arena.h>

#include <cmath>

#include "procedures/eye/eye_mesh.hpp"
#include "procedures/lens/fragment_lens.hpp"

namespace phaco::lens {
namespace {

constexpr double kDt = 1.0 / 120.0;

FragmentLensSettings settings() {
  FragmentLensSettings s;
  s.bounds = lens_tools::eye_bounds(4.7, 1.8, -2.7, 4.8, 6.5, 2.6);
  s.erosion.half_angle_rad = 0.3;
  s.erosion.reach_mm = 8.0;
  s.erosion.rate_per_s = 1e5;  // p = 1 inside the cone: a clean cut
  s.nucleus_hardness = 0.0;
  s.contact.h = 0.3f;
  s.contact.stiffness = 1.0f;  // far above m/dt²: the contact move is bounded (fragment_lens.cpp)
  return s;
}

const TetMesh& lens_mesh() {
  static const TetMesh m =
      eye::make_lens_tets(eye::default_eye_params(), eye::resolution_for_level(0));
  return m;
}

// The phaco tip above the lens at x = 0 sweeping across y with its cone pointing down cuts the
// lens in two; then 200 steps of nothing but gravity, contact, constraints and shape matching.
FragmentLens cut_in_two() {
  FragmentLens l = make_fragment_lens(lens_mesh(), settings());
  const CounterRng rng(11, 3);
  uint64_t frame = 0;
  for (int k = 0; k <= 100; ++k, ++frame) {
    LensTools tools;
    tools.phaco = lens_tools::PhacoTip{Vec3(0.0, -5.0 + 0.1 * k, 3.0), -Vec3::UnitZ(), 1.0};
    step_fragment_lens(l, tools, rng, frame, kDt);
  }
  for (int k = 0; k < 200; ++k, ++frame) step_fragment_lens(l, {}, rng, frame, kDt);
  return l;
}

TEST(FragmentLens, AsleepUntilATouchNothingMoves) {
  FragmentLens l = make_fragment_lens(lens_mesh(), settings());
  const std::vector<float> x0 = l.cells.x, z0 = l.cells.z;
  const CounterRng rng(1);
  for (uint64_t f = 0; f < 50; ++f) step_fragment_lens(l, {}, rng, f, kDt);
  EXPECT_FALSE(l.awake);
  EXPECT_EQ(l.cells.x, x0);
  EXPECT_EQ(l.cells.z, z0);
  EXPECT_EQ(l.fragments.count, 1u);
}

TEST(FragmentLens, ACutThroughTheLensMakesRigidFragmentsThatStayInsideAndApart) {
  FragmentLens l = cut_in_two();
  EXPECT_GT(l.cells_removed, 50u);
  ASSERT_GE(l.fragments.count, 2u);
  // The labels kept up removal by removal (splits confirmed locally) are a fresh painting's.
  Fragments fresh;
  simplex::FragmentScratch scratch;
  simplex::label_fragments_painting(l.cells, fresh, scratch);
  EXPECT_EQ(l.fragments.label, fresh.label);
  EXPECT_EQ(l.fragments.count, fresh.count);
  const uint32_t n = l.cells.size();
  for (uint32_t c = 0; c < n; ++c) {
    if (!l.cells.alive[c]) continue;
    ASSERT_TRUE(std::isfinite(l.cells.x[c]) && std::isfinite(l.cells.y[c]) &&
                std::isfinite(l.cells.z[c]));
    // Gravity sinks a resting fragment 892·dt² ≈ 0.06 mm into the capsule each step before the
    // constraint and the rigid fit take it back: inside to within ~2/3 of a level-0 cell (0.31 mm).
    EXPECT_TRUE(lens_tools::inside_bounds(Vec3(l.cells.x[c], l.cells.y[c], l.cells.z[c]),
                                          l.settings.bounds, 0.2))
        << "cell " << c;
  }
  // Rigid: within each large fragment, distances between members are their rest distances.
  double worst = 0;
  for (uint32_t f = 0; f < l.fragments.count; ++f) {
    if (l.fragments.size_of(f) < 10) continue;
    const uint32_t* m = &l.fragments.members[l.fragments.offsets[f]];
    for (uint32_t i = 0; i + 7 < l.fragments.size_of(f); i += 7) {
      const uint32_t a = m[i], b = m[i + 7];
      const double now = std::hypot(l.cells.x[a] - l.cells.x[b], l.cells.y[a] - l.cells.y[b],
                                    l.cells.z[a] - l.cells.z[b]);
      const double rest =
          std::hypot(l.cells.rest_x[a] - l.cells.rest_x[b], l.cells.rest_y[a] - l.cells.rest_y[b],
                     l.cells.rest_z[a] - l.cells.rest_z[b]);
      worst = std::max(worst, std::abs(now - rest));
    }
  }
  EXPECT_LT(worst, 0.02) << "fragments keep their shape (mm)";
  // Apart: no two boundary cells of different fragments closer than half the contact support.
  float closest = 1e9f;
  for (uint32_t a = 0; a < n; ++a) {
    if (!l.cells.alive[a]) continue;
    for (uint32_t b = a + 1; b < n; ++b) {
      if (!l.cells.alive[b] || l.fragments.label[a] == l.fragments.label[b]) continue;
      closest =
          std::min(closest, std::hypot(l.cells.x[a] - l.cells.x[b], l.cells.y[a] - l.cells.y[b],
                                       l.cells.z[a] - l.cells.z[b]));
    }
  }
  EXPECT_GT(closest, 0.5f * l.settings.contact.h);
}

TEST(FragmentLens, OneAndTwoThreadsGiveTheSameLens) {
  FragmentLens one, two;
  tbb::task_arena(1).execute([&] { one = cut_in_two(); });
  tbb::task_arena(2).execute([&] { two = cut_in_two(); });
  EXPECT_EQ(one.cells.x, two.cells.x);
  EXPECT_EQ(one.cells.y, two.cells.y);
  EXPECT_EQ(one.cells.z, two.cells.z);
  EXPECT_EQ(one.fragments.label, two.fragments.label);
}

}  // namespace
}  // namespace phaco::lens
