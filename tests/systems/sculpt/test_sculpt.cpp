// systems/sculpt: removal by the phaco tip, the surface list after every step, the two
// broadphases, the seeded walk against brute force, locality.
#include <gtest/gtest.h>

#include <algorithm>
#include <set>

#include "sculpt_fixture.hpp"

namespace phaco::sculpt::test {
namespace {

std::set<uint32_t> brute_surface(const TetTopology& topo) {
  std::set<uint32_t> s;
  for (uint32_t t = 0; t < topo.tet_count; ++t)
    if (tet_on_surface(topo, t)) s.insert(t);
  return s;
}

// What a scan of every alive tet would remove for this tip.
std::set<uint32_t> brute_hits(const TetTopology& topo, std::span<const Vec3> x,
                              const SculptTip& tip, Narrowphase method) {
  std::set<uint32_t> s;
  if (!(tip.radius_mm > 0.0)) return s;
  const TipCapsule cap{tip.previous_centre, tip.centre, tip.radius_mm};
  for (uint32_t t = 0; t < topo.tet_count; ++t)
    if (topo.alive[t] && bound_touches_tip(topo, t, cap) &&
        narrowphase_hit(topo, x, t, cap, method))
      s.insert(t);
  return s;
}

TEST(Sculpt, RadiusFollowsUltrasoundPower) {
  EXPECT_EQ(sculpt_radius_mm(2.0, 1.0), 0.0);  // pedal 2: irrigation/aspiration only
  EXPECT_DOUBLE_EQ(sculpt_radius_mm(3.0, 0.0), 0.5 * kPhacoTipRadiusMm);
  EXPECT_DOUBLE_EQ(sculpt_radius_mm(3.0, 1.0), kPhacoTipRadiusMm);
  EXPECT_DOUBLE_EQ(sculpt_radius_mm(3.0, 0.5), 0.75 * kPhacoTipRadiusMm);
  EXPECT_DOUBLE_EQ(sculpt_radius_mm(3.0, 7.0), kPhacoTipRadiusMm);
}

TEST(Sculpt, TipOutsideOrWithoutPowerRemovesNothing) {
  const TetMesh& mesh = lens_tets(0);
  TetTopology topo = build_tet_topology(mesh);
  SculptState state = make_sculpt_state(topo, {});
  EXPECT_TRUE(
      sculpt_step(topo, mesh.vertices, state, {Vec3(0, 0, 4), Vec3(0, 0, 4), 0.45}).empty());
  EXPECT_TRUE(sculpt_step(topo, mesh.vertices, state, {Vec3(0, 0, 0), Vec3(0, 0, 0), 0.0}).empty());
  EXPECT_EQ(topo.alive_count, topo.tet_count);
  EXPECT_FALSE(
      sculpt_step(topo, mesh.vertices, state, {Vec3(0, 0, 0), Vec3(0, 0, 0), 0.45}).empty());
}

struct FuzzCase {
  Broadphase broadphase;
  Narrowphase narrowphase;
};

class SculptFuzz : public ::testing::TestWithParam<FuzzCase> {};

// After every step: the surface list is the brute-force surface, the counts agree, and the walk
// removed exactly what a scan of all tets would.
TEST_P(SculptFuzz, SurfaceAndRemovalsEqualBruteForceAfterEveryStep) {
  const TetMesh& mesh = lens_tets(0);
  for (uint64_t seed : {1u, 2u, 3u}) {
    TetTopology topo = build_tet_topology(mesh);
    SculptOptions options;
    options.broadphase = GetParam().broadphase;
    options.narrowphase = GetParam().narrowphase;
    SculptState state = make_sculpt_state(topo, options);
    uint32_t removed_total = 0, continued = 0;
    const auto track = random_sweep(seed, 300);
    for (size_t s = 0; s < track.size(); ++s) {
      const std::set<uint32_t> expected =
          brute_hits(topo, mesh.vertices, track[s], options.narrowphase);
      const auto removed = sculpt_step(topo, mesh.vertices, state, track[s]);
      ASSERT_EQ(std::set<uint32_t>(removed.begin(), removed.end()), expected)
          << "seed " << seed << " step " << s;
      ASSERT_EQ(removed.size(), expected.size());  // each once
      removed_total += static_cast<uint32_t>(removed.size());
      continued += (!removed.empty() && !state.stats.used_broadphase) ? 1 : 0;
      const std::set<uint32_t> listed(topo.surface.begin(), topo.surface.end());
      ASSERT_EQ(listed.size(), topo.surface.size());
      ASSERT_EQ(listed, brute_surface(topo)) << "seed " << seed << " step " << s;
      for (size_t i = 0; i < topo.surface.size(); ++i)
        ASSERT_EQ(topo.surface_slot[topo.surface[i]], i);
      ASSERT_EQ(topo.alive_count,
                static_cast<uint32_t>(std::count(topo.alive.begin(), topo.alive.end(), 1)));
      ASSERT_EQ(topo.alive_count + removed_total, topo.tet_count);
    }
    EXPECT_GT(removed_total, 150u) << "the sweep must actually sculpt";
    EXPECT_GT(continued, 50u) << "most steps continue from the last removals";
  }
}

INSTANTIATE_TEST_SUITE_P(Methods, SculptFuzz,
                         ::testing::Values(FuzzCase{Broadphase::Octree,
                                                    Narrowphase::CentreInSphere},
                                           FuzzCase{Broadphase::Dbvt, Narrowphase::CentreInSphere},
                                           FuzzCase{Broadphase::Octree, Narrowphase::ExactGjk},
                                           FuzzCase{Broadphase::Dbvt, Narrowphase::ExactMpr}),
                         [](const auto& info) {
                           return std::string(to_string(info.param.broadphase)) + "_" +
                                  to_string(info.param.narrowphase);
                         });

std::vector<std::vector<uint32_t>> run(const TetMesh& mesh, const std::vector<SculptTip>& track,
                                       const SculptOptions& options) {
  TetTopology topo = build_tet_topology(mesh);
  SculptState state = make_sculpt_state(topo, options);
  std::vector<std::vector<uint32_t>> out;
  for (const SculptTip& tip : track) {
    const auto r = sculpt_step(topo, mesh.vertices, state, tip);
    out.emplace_back(r.begin(), r.end());
  }
  return out;
}

TEST(Sculpt, OctreeAndDbvtRemoveTheSameTetsInTheSameOrder) {
  const TetMesh& mesh = lens_tets(1);
  const auto track = random_sweep(11, 300);
  for (Narrowphase np : {Narrowphase::CentreInSphere, Narrowphase::ExactGjk}) {
    SculptOptions a, b;
    a.broadphase = Broadphase::Octree, b.broadphase = Broadphase::Dbvt;
    a.narrowphase = b.narrowphase = np;
    EXPECT_EQ(run(mesh, track, a), run(mesh, track, b)) << to_string(np);
  }
}

TEST(Sculpt, ContinuingFromLastRemovalsEqualsBroadphaseEveryStep) {
  const TetMesh& mesh = lens_tets(1);
  const auto track = random_sweep(12, 300);
  SculptOptions walk, every;
  every.continue_from_last = false;
  const auto x = run(mesh, track, walk), y = run(mesh, track, every);
  ASSERT_EQ(x.size(), y.size());
  for (size_t s = 0; s < x.size(); ++s)
    EXPECT_EQ(std::set<uint32_t>(x[s].begin(), x[s].end()),
              std::set<uint32_t>(y[s].begin(), y[s].end()))
        << "step " << s;
}

TEST(Sculpt, ExactTestRemovesASupersetOfTheCentreTest) {
  const TetMesh& mesh = lens_tets(1);
  const auto track = random_sweep(13, 300);
  SculptOptions centre, exact;
  exact.narrowphase = Narrowphase::ExactGjk;
  std::set<uint32_t> by_centre, by_exact;
  for (const auto& step : run(mesh, track, centre)) by_centre.insert(step.begin(), step.end());
  for (const auto& step : run(mesh, track, exact)) by_exact.insert(step.begin(), step.end());
  EXPECT_TRUE(std::includes(by_exact.begin(), by_exact.end(), by_centre.begin(), by_centre.end()));
  EXPECT_GT(by_exact.size(), by_centre.size() + by_centre.size() / 10);
}

TEST(Sculpt, SurfaceTrianglesCloseTheRemainingLens) {
  const TetMesh& mesh = lens_tets(0);
  TetTopology topo = build_tet_topology(mesh);
  SculptState state = make_sculpt_state(topo, {});
  for (const SculptTip& tip : random_sweep(21, 200)) sculpt_step(topo, mesh.vertices, state, tip);
  std::vector<std::array<uint32_t, 3>> faces;
  surface_triangles(topo, faces);
  // Closed and outward: the divergence-theorem volume of the faces equals the alive tets' volume.
  double enclosed = 0.0, alive = 0.0;
  for (const auto& f : faces)
    enclosed += mesh.vertices[f[0]].dot(mesh.vertices[f[1]].cross(mesh.vertices[f[2]])) / 6.0;
  for (uint32_t t = 0; t < topo.tet_count; ++t) alive += topo.alive[t] ? topo.volume[t] : 0.0;
  ASSERT_LT(topo.alive_count, topo.tet_count);
  EXPECT_NEAR(enclosed, alive, 1e-4 * alive);
}

// The work of a step follows the tets near the tip, not the mesh: per tet the tip's bounding test
// touches, level 2 (4x the tets) costs no more than level 0.
TEST(Sculpt, StepCostIsLocal) {
  const std::vector<Vec3> path = {Vec3(-3.0, 0.0, 2.5), Vec3(-3.0, 0.0, 0.8), Vec3(3.0, 0.0, 0.8),
                                  Vec3(3.0, 0.5, 0.4), Vec3(-3.0, 0.5, 0.4)};
  const auto track = sample_path(path, 0.45, 0.05);
  double ratio[2] = {0, 0}, work_per_tet[2] = {0, 0};
  for (int i = 0; i < 2; ++i) {
    const TetMesh& mesh = lens_tets(2 * i);
    TetTopology topo = build_tet_topology(mesh);
    SculptState state = make_sculpt_state(topo, {});
    double work = 0, touched = 0;
    for (const SculptTip& tip : track) {
      const TipCapsule cap{tip.previous_centre, tip.centre, tip.radius_mm};
      for (uint32_t t = 0; t < topo.tet_count; ++t)
        touched += bound_touches_tip(topo, t, cap) ? 1 : 0;
      sculpt_step(topo, mesh.vertices, state, tip);
      work += state.stats.work();
    }
    ratio[i] = work / touched;
    work_per_tet[i] = work / static_cast<double>(track.size()) / topo.tet_count;
  }
  EXPECT_LT(ratio[1], 1.5 * ratio[0]) << ratio[0] << " " << ratio[1];
  EXPECT_LT(ratio[1], 3.0);
  EXPECT_LT(work_per_tet[1], 0.5 * work_per_tet[0]);  // a smaller share of a bigger mesh
}

}  // namespace
}  // namespace phaco::sculpt::test
