// Active node set: exact k-hop ball sizes on known grids, the springs it selects, the wake and
// sleep rules, determinism and no allocation after warm-up.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>

#include "procedures/eye/eye_mesh.hpp"
#include "systems/active_nodes/active_nodes.hpp"
#include "systems/springs/springs.hpp"

namespace phaco {
namespace {

using active_nodes::ActiveSet;
using active_nodes::WakeInputs;

struct Grid {
  int n;
  Particles particles;
  Springs springs;
  SpringGraph graph;
  uint32_t at(int r, int c) const { return static_cast<uint32_t>(r * n + c); }
};

// n × n unit grid at rest (every spring at its rest length); `king` adds both diagonals, so every
// interior node has 8 neighbours, else 4.
Grid make_grid(int n, bool king) {
  Grid g{n};
  table_append(g.particles, static_cast<uint32_t>(n * n));
  for (int r = 0; r < n; ++r)
    for (int c = 0; c < n; ++c)
      g.particles.x[g.at(r, c)] = float(c), g.particles.y[g.at(r, c)] = float(r);
  auto link = [&](uint32_t a, uint32_t b) {
    const uint32_t e = table_add(g.springs);
    g.springs.i[e] = std::min(a, b), g.springs.j[e] = std::max(a, b);
    const float dx = g.particles.x[b] - g.particles.x[a], dy = g.particles.y[b] - g.particles.y[a];
    g.springs.rest_length[e] = std::sqrt(dx * dx + dy * dy);
    g.springs.stiffness[e] = 1.0f;
  };
  for (int r = 0; r < n; ++r)
    for (int c = 0; c < n; ++c) {
      if (c + 1 < n) link(g.at(r, c), g.at(r, c + 1));
      if (r + 1 < n) link(g.at(r, c), g.at(r + 1, c));
      if (king && r + 1 < n && c + 1 < n) link(g.at(r, c), g.at(r + 1, c + 1));
      if (king && r + 1 < n && c > 0) link(g.at(r, c), g.at(r + 1, c - 1));
    }
  g.graph = springs::build_spring_graph(g.springs, g.particles.slots.size());
  return g;
}

size_t ball(const Grid& g, std::vector<uint32_t> seeds, uint32_t k) {
  ActiveSet set;
  active_nodes::update_active_set(g.graph, seeds, k, {}, set);
  return set.particles.size();
}

TEST(ActiveNodes, KHopBallsOnGridsHaveTheExactSize) {
  const Grid four = make_grid(31, false), eight = make_grid(31, true);
  for (uint32_t k = 0; k <= 7; ++k) {
    EXPECT_EQ(ball(four, {four.at(15, 15)}, k), 2 * k * k + 2 * k + 1) << k;  // diamond
    EXPECT_EQ(ball(four, {four.at(0, 0)}, k), (k + 1) * (k + 2) / 2) << k;    // corner: a quarter
    EXPECT_EQ(ball(eight, {eight.at(15, 15)}, k), (2 * k + 1) * (2 * k + 1)) << k;  // square
  }
  // Seed 003: k = 5 → 120 nodes on its curvilinear mesh; the 8-neighbour grid gives 121.
  EXPECT_EQ(ball(eight, {eight.at(15, 15)}, 5), 121u);
}

TEST(ActiveNodes, SeveralSeedsGiveTheUnionOfTheirBalls) {
  const Grid g = make_grid(31, false);
  const std::vector<uint32_t> seeds = {g.at(10, 10), g.at(14, 13), g.at(29, 2)};
  size_t expected = 0;
  for (int r = 0; r < 31; ++r)
    for (int c = 0; c < 31; ++c) {
      bool in = false;
      for (uint32_t s : seeds) in |= std::abs(r - int(s) / 31) + std::abs(c - int(s) % 31) <= 4;
      expected += in;
    }
  EXPECT_EQ(ball(g, seeds, 4), expected);
}

TEST(ActiveNodes, OutputsAreSortedAndTheSpringsAreThoseWithAnActiveEnd) {
  const Grid g = make_grid(25, true);
  ActiveSet set;
  const uint32_t seeds[] = {g.at(3, 20), g.at(12, 12)};
  active_nodes::update_active_set(g.graph, seeds, 3, {}, set);
  EXPECT_TRUE(std::is_sorted(set.particles.begin(), set.particles.end()));
  EXPECT_TRUE(std::adjacent_find(set.particles.begin(), set.particles.end()) ==
              set.particles.end());
  std::vector<uint32_t> expected;
  for (uint32_t e = 0; e < g.springs.slots.size(); ++e) {
    const bool a = std::binary_search(set.particles.begin(), set.particles.end(), g.springs.i[e]);
    const bool b = std::binary_search(set.particles.begin(), set.particles.end(), g.springs.j[e]);
    if (a || b) expected.push_back(e);
  }
  EXPECT_EQ(set.springs, expected);
}

TEST(ActiveNodes, NeighbourMotionWakesAndQuietParticlesFallAsleep) {
  Grid g = make_grid(21, false);
  ActiveSet set;
  const uint32_t seed[] = {g.at(10, 10)};
  active_nodes::update_active_set(g.graph, seed, 1, {}, set);  // the grasp: 5 nodes
  ASSERT_EQ(set.particles.size(), 5u);

  // Released: no seed. (10, 11) moved 2 µm in the last step, above a 1 µm threshold.
  g.particles.vx[g.at(10, 11)] = 0.2f;  // mm/s × 0.01 s
  WakeInputs wake{.particles = &g.particles, .dt_s = 0.01, .motion_threshold_mm = 1e-3};
  active_nodes::update_active_set(g.graph, {}, 1, wake, set);
  const std::vector<uint32_t> expected = {g.at(9, 11), g.at(10, 10), g.at(10, 11), g.at(10, 12),
                                          g.at(11, 11)};
  EXPECT_EQ(set.particles, expected);
  EXPECT_EQ(set.woken, 5u);
  const std::vector<uint32_t> asleep = {g.at(9, 10), g.at(10, 9), g.at(11, 10)};
  EXPECT_EQ(set.fell_asleep, asleep);

  // Everything quiet: all fall asleep.
  g.particles.vx[g.at(10, 11)] = 0.05f;  // 0.5 µm
  active_nodes::update_active_set(g.graph, {}, 1, wake, set);
  EXPECT_TRUE(set.particles.empty());
  EXPECT_TRUE(set.springs.empty());
  EXPECT_EQ(set.fell_asleep, expected);
}

TEST(ActiveNodes, ForceOnTheSleepingFrontierWakesIt) {
  Grid g = make_grid(21, false);
  ActiveSet set;
  const uint32_t seed[] = {g.at(10, 10)};
  active_nodes::update_active_set(g.graph, seed, 1, {}, set);
  WakeInputs wake{
      .particles = &g.particles, .dt_s = 0.01, .springs = &g.springs, .force_threshold_mn = 0.05};

  // At rest every spring is slack: nothing wakes beyond the ball.
  active_nodes::update_active_set(g.graph, seed, 1, wake, set);
  EXPECT_EQ(set.particles.size(), 5u);
  EXPECT_EQ(set.woken, 0u);

  // Frontier node (10, 12) displaced 0.1 mm along x: springs k = 1 pull it back with 0.2 mN.
  g.particles.x[g.at(10, 12)] += 0.1f;
  active_nodes::update_active_set(g.graph, seed, 1, wake, set);
  EXPECT_EQ(set.woken, 1u);
  EXPECT_TRUE(std::binary_search(set.particles.begin(), set.particles.end(), g.at(10, 12)));
  g.particles.x[g.at(10, 12)] -= 0.1f;

  // An external load (tool contact) on another frontier node.
  Forces external;
  external.resize_zero(g.particles.slots.size());
  external.fz[g.at(8, 10)] = 0.06f;
  wake.external = &external;
  active_nodes::update_active_set(g.graph, seed, 1, wake, set);
  EXPECT_TRUE(std::binary_search(set.particles.begin(), set.particles.end(), g.at(8, 10)));
  external.fz[g.at(8, 10)] = 0.04f;  // below the threshold
  active_nodes::update_active_set(g.graph, seed, 1, wake, set);
  EXPECT_FALSE(std::binary_search(set.particles.begin(), set.particles.end(), g.at(8, 10)));
}

TEST(ActiveNodes, DeterministicAndAllocationFreeAfterWarmUp) {
  const Grid g = make_grid(41, true);
  const uint32_t a[] = {g.at(20, 20)}, b[] = {g.at(5, 30), g.at(35, 3)};
  ActiveSet fresh, reused;
  active_nodes::update_active_set(g.graph, a, 6, {}, fresh);
  active_nodes::update_active_set(g.graph, b, 6, {}, reused);  // warm-up with larger outputs
  active_nodes::update_active_set(g.graph, a, 6, {}, reused);
  EXPECT_EQ(fresh.particles, reused.particles);
  EXPECT_EQ(fresh.springs, reused.springs);
  const uint32_t* particles = reused.particles.data();
  const uint32_t* springs_data = reused.springs.data();
  const size_t capacity = reused.springs.capacity();
  for (int s = 0; s < 4; ++s)
    active_nodes::update_active_set(
        g.graph, s % 2 ? std::span<const uint32_t>(a) : std::span<const uint32_t>(b), 6, {},
        reused);
  EXPECT_EQ(reused.particles.data(), particles);
  EXPECT_EQ(reused.springs.data(), springs_data);
  EXPECT_EQ(reused.springs.capacity(), capacity);
}

TEST(ActiveNodes, FiveHopsOnTheCapsuleMatchSeed003) {
  // Level 1 has about 2000 vertices, as seed 003's mesh (2005).
  const SurfaceMesh mesh = eye::make_capsule(
      eye::default_eye_params(), eye::resolution_for_level(1), eye::CapsuleLayout::Curvilinear);
  Particles p;
  Triangles t;
  table_append(p, static_cast<uint32_t>(mesh.vertices.size()));
  for (size_t i = 0; i < mesh.vertices.size(); ++i)
    p.x[i] = float(mesh.vertices[i].x()), p.y[i] = float(mesh.vertices[i].y()),
    p.z[i] = float(mesh.vertices[i].z());
  table_append(t, static_cast<uint32_t>(mesh.triangles.size()));
  for (size_t i = 0; i < mesh.triangles.size(); ++i)
    t.a[i] = mesh.triangles[i][0], t.b[i] = mesh.triangles[i][1], t.c[i] = mesh.triangles[i][2];
  const Springs s = springs::build_springs(p, t, {});
  const SpringGraph g = springs::build_spring_graph(s, p.slots.size());
  // Seeds at half the radius on four sides and the centre.
  double radius = 0.0;
  for (const Vec3& v : mesh.vertices) radius = std::max(radius, std::hypot(v.x(), v.y()));
  size_t smallest = SIZE_MAX, largest = 0;
  for (double angle : {0.0, 1.6, 3.1, 4.7}) {
    uint32_t seed = 0;
    double best = 1e9;
    for (uint32_t i = 0; i < mesh.vertices.size(); ++i) {
      const double d = std::hypot(mesh.vertices[i].x() - 0.5 * radius * std::cos(angle),
                                  mesh.vertices[i].y() - 0.5 * radius * std::sin(angle));
      if (d < best) best = d, seed = i;
    }
    ActiveSet set;
    const uint32_t seeds[] = {seed};
    active_nodes::update_active_set(g, seeds, 5, {}, set);
    smallest = std::min(smallest, set.particles.size());
    largest = std::max(largest, set.particles.size());
  }
  std::printf(
      "[ figures  ] capsule level 1 (%zu vertices): 5-hop sets of %zu to %zu nodes (seed 003: 120 "
      "of 2005)\n",
      mesh.vertices.size(), smallest, largest);
  // Interior valence 4 or 8: the ball lies between the 4-neighbour diamond and the 8-neighbour
  // square.
  EXPECT_GE(smallest, 61u);
  EXPECT_LE(largest, 121u);
}

}  // namespace
}  // namespace phaco
