// Issue 17 item 1: after cuts, the physics structure patched where the cuts touched it — new
// springs appended to the force blocks' tail, removed ones tombstones of stiffness 0, the spring
// graph's touched rows patched (springs::patch_spring_graph) — gives the same physics as a full
// rebuild (compaction, sort by (i, j), block plan, fresh graph): the same live springs, graph rows
// equal as sets, forces equal within float rounding. And the compaction, done later, leaves the
// same physics.
#include <gtest/gtest.h>

#include <cmath>
#include <set>
#include <tuple>
#include <vector>

#include "engine/core/rng.hpp"
#include "systems/cut/spring_order.hpp"
#include "tests/support/grid_mesh.hpp"
#include "tests/systems/cut/cut_sheet.hpp"

namespace phaco::cut {
namespace {

using SpringSet = std::set<std::tuple<uint32_t, uint32_t, float, float>>;

SpringSet live_springs(const Springs& s) {
  SpringSet out;
  for (uint32_t e = 0; e < s.slots.size(); ++e)
    if (s.slots.alive(e)) out.emplace(s.i[e], s.j[e], s.rest_length[e], s.stiffness[e]);
  return out;
}

Forces spring_forces(const Springs& s, const SpringBlocks& b, const Particles& p) {
  Forces f;
  f.resize_zero(p.slots.size());
  springs::add_spring_forces(s, b, SpringLaw::Linear, p, f);
  return f;
}

// Forces from two summation orders: equal up to float rounding of the few terms per particle.
void expect_same_forces(const Forces& a, const Forces& b, const Particles& p, const char* what) {
  ASSERT_EQ(a.fx.size(), b.fx.size()) << what;
  for (uint32_t v = 0; v < p.slots.size(); ++v) {
    if (!p.slots.alive(v)) continue;
    const float fa[3] = {a.fx[v], a.fy[v], a.fz[v]}, fb[3] = {b.fx[v], b.fy[v], b.fz[v]};
    for (int k = 0; k < 3; ++k)
      ASSERT_NEAR(fa[k], fb[k], 1e-4f * (1.0f + std::fabs(fb[k])))
          << what << ": particle " << v << " axis " << k;
  }
}

// A sheet under cuts with its physics structure kept up to date as the scene does it.
struct PatchedSheet {
  test::CutSheet sheet;
  SpringBlocks blocks;
  SpringGraph graph;

  explicit PatchedSheet(const SurfaceMesh& mesh) : sheet(test::cut_sheet(mesh)) {
    blocks = springs::plan_blocks(sheet.springs, sheet.particles.slots.size(), 16);
    graph = springs::build_spring_graph(sheet.springs, sheet.particles.slots.size());
    sheet.topology.added_springs.clear(), sheet.topology.removed_springs.clear();
  }
  void patch() {
    springs::patch_spring_graph(graph, sheet.springs, sheet.particles.slots.size(),
                                sheet.topology.removed_springs, sheet.topology.added_springs);
    sheet.topology.added_springs.clear(), sheet.topology.removed_springs.clear();
  }
  void compact() {
    CutMesh m = sheet.mesh();
    compact_and_sort_springs(m);
    blocks = springs::plan_blocks(sheet.springs, sheet.particles.slots.size(), 16);
    graph = springs::build_spring_graph(sheet.springs, sheet.particles.slots.size());
  }
};

// Random straight and curving cuts across a jittered 24 × 24 sheet.
void random_cut(PatchedSheet& ps, const CounterRng& rng, uint64_t path) {
  auto u = [&](uint32_t draw) { return rng.uniform_double(path, draw, 0); };
  CutSettings settings;
  settings.snap.vertex_snap_mm = 0.1;
  settings.snap.edge_snap_mm = 0.05;
  Vec3 x(3.0 + 17.0 * u(0), 3.0 + 17.0 * u(1), 0.0);
  double heading = 6.283185307179586 * u(2);
  const double turn = (u(3) - 0.5) * 0.6, speed = 0.3 + 0.9 * u(4);
  const int samples = 3 + static_cast<int>(12 * u(5));
  CutMesh m = ps.sheet.mesh();
  CutPath cut_path;
  EditLog log;
  for (int k = 0; k < samples; ++k) {
    const SegmentReport r = cut_towards(m, cut_path, Vec3(x.x(), x.y(), 0.01), settings, log);
    if (r.reached_boundary) break;
    x += speed * Vec3(std::cos(heading), std::sin(heading), 0.0);
    heading += turn;
  }
}

// The sheet pulled out of its plane so every spring carries a force.
void deform(Particles& p) {
  for (uint32_t v = 0; v < p.slots.size(); ++v)
    p.z[v] = 0.05f * std::sin(0.7f * p.x[v]) * std::cos(0.5f * p.y[v]);
}

TEST(IncrementalRefresh, RandomCutsOnTheFlatSheetMatchAFullRebuild) {
  PatchedSheet ps(phaco::test::grid_mesh(24, 0.2));
  const CounterRng rng(0x17, 1);
  const uint32_t planned = ps.sheet.springs.slots.size();
  for (uint64_t path = 0; path < 40; ++path) {
    random_cut(ps, rng, path);
    ps.patch();
    ASSERT_TRUE(test::sound(ps.sheet)) << "path " << path;
    const uint32_t n = ps.sheet.particles.slots.size();
    ASSERT_EQ(topology_check::check_spring_structure(ps.sheet.springs, ps.blocks, ps.graph, n), "")
        << "path " << path;
    // The patched graph against a fresh build of the same table: every row the same, as a set.
    const SpringGraph fresh = springs::build_spring_graph(ps.sheet.springs, n);
    for (uint32_t v = 0; v < n; ++v) {
      auto a = springs::graph_row(ps.graph, v), b = springs::graph_row(fresh, v);
      std::sort(a.begin(), a.end()), std::sort(b.begin(), b.end());
      ASSERT_EQ(a, b) << "path " << path << ", particle " << v;
    }
    // Forces and springs against a full rebuild on a copy.
    PatchedSheet full = ps;
    full.compact();
    deform(ps.sheet.particles);
    deform(full.sheet.particles);
    EXPECT_EQ(live_springs(ps.sheet.springs), live_springs(full.sheet.springs)) << "path " << path;
    expect_same_forces(spring_forces(ps.sheet.springs, ps.blocks, ps.sheet.particles),
                       spring_forces(full.sheet.springs, full.blocks, full.sheet.particles),
                       ps.sheet.particles, "incremental vs full rebuild");
    for (uint32_t v = 0; v < n; ++v) ps.sheet.particles.z[v] = 0.0f;  // back to the cut's plane
  }
  EXPECT_GT(ps.sheet.springs.slots.size(), planned) << "the cuts appended springs to the tail";
  EXPECT_GT(ps.sheet.springs.slots.size(), ps.sheet.springs.slots.live_count())
      << "and left tombstones";
  EXPECT_EQ(ps.blocks.tail_begin(), planned) << "the plan was not redone";
}

TEST(IncrementalRefresh, CompactionLaterLeavesTheSamePhysics) {
  PatchedSheet ps(phaco::test::grid_mesh(24, 0.2));
  const CounterRng rng(0x71, 1);
  for (uint64_t path = 0; path < 20; ++path) random_cut(ps, rng, path), ps.patch();
  deform(ps.sheet.particles);
  const Forces before = spring_forces(ps.sheet.springs, ps.blocks, ps.sheet.particles);
  const SpringSet springs_before = live_springs(ps.sheet.springs);
  ASSERT_GT(ps.sheet.springs.slots.size(), ps.blocks.tail_begin());
  ps.compact();
  EXPECT_EQ(ps.sheet.springs.slots.size(), ps.sheet.springs.slots.live_count())
      << "no tombstone left";
  EXPECT_EQ(ps.blocks.tail_begin(), ps.sheet.springs.slots.size()) << "no tail left";
  EXPECT_EQ(live_springs(ps.sheet.springs), springs_before);
  EXPECT_TRUE(test::sound(ps.sheet));
  EXPECT_EQ(topology_check::check_spring_structure(ps.sheet.springs, ps.blocks, ps.graph,
                                                   ps.sheet.particles.slots.size()),
            "");
  expect_same_forces(spring_forces(ps.sheet.springs, ps.blocks, ps.sheet.particles), before,
                     ps.sheet.particles, "after compaction");
  // Cutting goes on after the compaction: the spring index was rebuilt with the new order.
  for (uint64_t path = 20; path < 30; ++path) random_cut(ps, rng, path), ps.patch();
  EXPECT_TRUE(test::sound(ps.sheet));
  EXPECT_EQ(topology_check::check_spring_structure(ps.sheet.springs, ps.blocks, ps.graph,
                                                   ps.sheet.particles.slots.size()),
            "");
}

TEST(IncrementalRefresh, StructureCheckFindsAMissingRowEntryAndAPullingTombstone) {
  PatchedSheet ps(phaco::test::grid_mesh(8, 0.0));
  const uint32_t n = ps.sheet.particles.slots.size();
  ASSERT_EQ(topology_check::check_spring_structure(ps.sheet.springs, ps.blocks, ps.graph, n), "");
  SpringGraph broken = ps.graph;
  --broken.row_size[5];
  EXPECT_NE(topology_check::check_spring_structure(ps.sheet.springs, ps.blocks, broken, n), "");
  Springs dead = ps.sheet.springs;
  table_remove(dead, 3);  // removed without the edit's zero stiffness
  EXPECT_NE(topology_check::check_spring_structure(dead, ps.blocks,
                                                   springs::build_spring_graph(dead, n), n),
            "");
}

}  // namespace
}  // namespace phaco::cut
