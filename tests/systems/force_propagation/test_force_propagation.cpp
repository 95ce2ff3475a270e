// Force propagation (seed 000 §5.1): locality, determinism, cost following the touched region,
// and convergence to equilibrium on a small sheet. Its error against the static equilibrium of a
// capsule-sized disc is in tests/procedures/reference/test_propagation_error.cpp.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <deque>
#include <vector>

#include "systems/force_propagation/force_propagation.hpp"
#include "systems/springs/springs.hpp"

namespace phaco::force_propagation {
namespace {

// n × n grid of spacing h in z = 0, each square split along alternating diagonals; border anchored.
struct Sheet {
  Particles particles;
  Triangles triangles;
  Springs springs;
  SpringGraph graph;
  uint32_t n = 0;
  uint32_t at(uint32_t i, uint32_t j) const { return j * n + i; }
};

Sheet make_sheet(uint32_t n, double h = 0.1, double prestretch = 0.05) {
  Sheet s;
  s.n = n;
  table_append(s.particles, n * n);
  for (uint32_t j = 0; j < n; ++j)
    for (uint32_t i = 0; i < n; ++i) {
      const uint32_t v = s.at(i, j);
      s.particles.x[v] = static_cast<float>(i * h);
      s.particles.y[v] = static_cast<float>(j * h);
      s.particles.z[v] = 0.0f;
      const bool border = i == 0 || j == 0 || i == n - 1 || j == n - 1;
      s.particles.kind[v] = border ? ParticleKind::Anchored : ParticleKind::Free;
      s.particles.inv_mass[v] = border ? 0.0f : 1.0e7f;
    }
  for (uint32_t j = 0; j + 1 < n; ++j)
    for (uint32_t i = 0; i + 1 < n; ++i) {
      const uint32_t a = s.at(i, j), b = s.at(i + 1, j), c = s.at(i + 1, j + 1), d = s.at(i, j + 1);
      const uint32_t t = table_append(s.triangles, 2);
      if ((i + j) % 2 == 0) {
        s.triangles.a[t] = a, s.triangles.b[t] = b, s.triangles.c[t] = c;
        s.triangles.a[t + 1] = a, s.triangles.b[t + 1] = c, s.triangles.c[t + 1] = d;
      } else {
        s.triangles.a[t] = a, s.triangles.b[t] = b, s.triangles.c[t] = d;
        s.triangles.a[t + 1] = b, s.triangles.b[t + 1] = c, s.triangles.c[t + 1] = d;
      }
    }
  s.springs = springs::build_springs(
      s.particles, s.triangles,
      springs::SpringMaterial{SpringLaw::Linear, StiffnessWeighting::AreaWeighted, 26.0,
                              prestretch});
  s.graph = springs::build_spring_graph(s.springs, n * n);
  return s;
}

// Hop distance from the sources by an independent breadth-first search.
std::vector<int> hops_from(const Sheet& s, const std::vector<uint32_t>& sources) {
  std::vector<int> hops(s.n * s.n, -1);
  std::deque<uint32_t> queue;
  for (uint32_t v : sources) hops[v] = 0, queue.push_back(v);
  while (!queue.empty()) {
    const uint32_t v = queue.front();
    queue.pop_front();
    for (uint32_t e = 0; e < s.springs.slots.size(); ++e) {
      const uint32_t w = s.springs.i[e] == v   ? s.springs.j[e]
                         : s.springs.j[e] == v ? s.springs.i[e]
                                               : UINT32_MAX;
      if (w != UINT32_MAX && hops[w] < 0) hops[w] = hops[v] + 1, queue.push_back(w);
    }
  }
  return hops;
}

// Grasp the centre vertex and lift it.
std::vector<uint32_t> lift_centre(Sheet& s, float dz) {
  const uint32_t c = s.at(s.n / 2, s.n / 2);
  s.particles.kind[c] = ParticleKind::Scripted;
  s.particles.z[c] += dz;
  return {c};
}

TEST(ForcePropagation, GraphListsEverySpringFromBothEnds) {
  const Sheet s = make_sheet(6);
  uint32_t entries = 0;
  for (uint32_t v = 0; v < s.graph.particle_count(); ++v) entries += s.graph.row_size[v];
  ASSERT_EQ(entries, 2 * s.springs.slots.size());
  for (uint32_t v = 0; v < s.n * s.n; ++v)
    for (uint32_t r = s.graph.begin(v); r < s.graph.end(v); ++r) {
      const uint32_t e = s.graph.spring[r], w = s.graph.neighbour[r];
      EXPECT_TRUE((s.springs.i[e] == v && s.springs.j[e] == w) ||
                  (s.springs.j[e] == v && s.springs.i[e] == w));
    }
}

TEST(ForcePropagation, MovesOnlyNodesWithinMaxLayersHops) {
  for (int max_layers : {1, 3, 6}) {
    Sheet s = make_sheet(31);
    const Particles before = s.particles;
    const auto sources = lift_centre(s, 0.1f);
    const auto hops = hops_from(s, sources);
    PropagationScratch scratch;
    const PropagationResult r = propagate(s.particles, s.springs, SpringLaw::Linear, s.graph,
                                          sources, {max_layers, 8, 1e-6, 1.0}, scratch);
    EXPECT_EQ(r.layers_reached, max_layers);
    uint32_t within = 0, moved_beyond = 0, moved = 0;
    for (uint32_t v = 0; v < s.n * s.n; ++v) {
      if (hops[v] >= 0 && hops[v] <= max_layers) ++within;
      const bool changed = s.particles.x[v] != before.x[v] || s.particles.y[v] != before.y[v] ||
                           s.particles.z[v] != before.z[v];
      if (changed && v != sources[0]) ++moved;
      if (changed && hops[v] > max_layers) ++moved_beyond;
    }
    EXPECT_EQ(moved_beyond, 0u) << max_layers;
    EXPECT_GT(moved, 0u);
    EXPECT_EQ(r.nodes_touched, within) << max_layers;
  }
}

TEST(ForcePropagation, WorkFollowsTheTouchedRegionNotTheMesh) {
  PropagationResult small, large;
  for (uint32_t n : {41u, 161u}) {
    Sheet s = make_sheet(n);
    const auto sources = lift_centre(s, 0.05f);
    PropagationScratch scratch;
    (n == 41 ? small : large) = propagate(s.particles, s.springs, SpringLaw::Linear, s.graph,
                                          sources, {8, 4, 1e-6, 1.0}, scratch);
  }
  // 1 681 against 25 921 vertices: the same neighbourhood is touched and relaxed.
  EXPECT_EQ(small.nodes_touched, large.nodes_touched);
  EXPECT_EQ(small.node_updates, large.node_updates);
  EXPECT_LT(large.nodes_touched, 161u * 161u / 50u);
}

TEST(ForcePropagation, IsDeterministicAndLeavesTheScratchClean) {
  Sheet a = make_sheet(25), b = make_sheet(25);
  const auto sa = lift_centre(a, 0.08f), sb = lift_centre(b, 0.08f);
  PropagationScratch scratch;
  const PropagationSettings settings{10, 6, 1e-6, 1.5};
  const PropagationResult ra =
      propagate(a.particles, a.springs, SpringLaw::Quadratic, a.graph, sa, settings, scratch);
  for (int32_t l : scratch.layer_of) ASSERT_EQ(l, -1);
  const PropagationResult rb =
      propagate(b.particles, b.springs, SpringLaw::Quadratic, b.graph, sb, settings, scratch);
  EXPECT_EQ(ra.node_updates, rb.node_updates);
  EXPECT_EQ(0, std::memcmp(a.particles.z.data(), b.particles.z.data(),
                           a.particles.z.size() * sizeof(float)));
  EXPECT_EQ(0, std::memcmp(a.particles.x.data(), b.particles.x.data(),
                           a.particles.x.size() * sizeof(float)));
}

TEST(ForcePropagation, AtEquilibriumNothingMovesAndTheFrontStops) {
  Sheet s = make_sheet(21);  // a uniformly stretched square grid is in equilibrium as built
  const Particles before = s.particles;
  const uint32_t c = s.at(10, 10);
  s.particles.kind[c] = ParticleKind::Scripted;
  PropagationScratch scratch;
  const PropagationResult r = propagate(s.particles, s.springs, SpringLaw::Linear, s.graph,
                                        std::vector<uint32_t>{c}, {16, 4, 1e-5, 1.0}, scratch);
  EXPECT_EQ(r.layers_reached, 1);
  EXPECT_EQ(r.sweeps_done, 1);
  for (uint32_t v = 0; v < s.n * s.n; ++v) EXPECT_NEAR(s.particles.z[v], before.z[v], 1e-7f);
}

TEST(ForcePropagation, ConvergesToEquilibriumWhenItCoversTheSheet) {
  Sheet s = make_sheet(15);
  const auto sources = lift_centre(s, 0.1f);
  PropagationScratch scratch;
  const PropagationResult r = propagate(s.particles, s.springs, SpringLaw::Linear, s.graph, sources,
                                        {64, 400, 1e-7, 1.7}, scratch);
  // Spring forces are about k·h·prestretch ≈ 0.1 mN; float positions leave ~1e-5 of that.
  EXPECT_LT(r.max_residual_mn, 2e-5);
  // The lifted sheet is a tent: a neighbour of the grasp rises, the border stays.
  EXPECT_GT(s.particles.z[s.at(8, 7)], 0.02f);
  EXPECT_EQ(s.particles.z[s.at(0, 7)], 0.0f);
}

TEST(ForcePropagation, PointForceSourceIsRelaxedUnderItsForce) {
  Sheet s = make_sheet(15);
  const uint32_t c = s.at(7, 7);
  const std::vector<uint32_t> sources{c};
  const float fx[1] = {0.0f}, fy[1] = {0.0f}, fz[1] = {-0.01f};
  const SourceForces forces{fx, fy, fz};
  PropagationScratch scratch;
  const PropagationResult r = propagate(s.particles, s.springs, SpringLaw::Linear, s.graph, sources,
                                        {64, 400, 1e-8, 1.7}, scratch, &forces);
  EXPECT_LT(s.particles.z[c], 0.0f);
  EXPECT_LT(r.max_residual_mn, 1e-4);
}

}  // namespace
}  // namespace phaco::force_propagation
