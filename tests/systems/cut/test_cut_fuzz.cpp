// Issue 4's fuzz test: at least 10,000 random cut paths on the capsule meshes of several levels,
// both layouts: random starts, lengths, angles and sampling speeds, paths forced through vertices
// and along edges, curving tear-like paths, paths crossing earlier cuts and running off the rim.
// After every path: zero invariant violations (systems/topology_check at its default thresholds)
// and the cut bookkeeping consistent with a rebuild; and the physics structure patched as the
// scene patches it (spring graph rows patched, new springs in the blocks' tail, tombstones) equal
// to a fresh build. Runs under ASan/UBSan in CI.
#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <tuple>

#include "engine/core/rng.hpp"
#include "procedures/eye/eye_mesh.hpp"
#include "procedures/eye/eye_params.hpp"
#include "procedures/eye/resolution.hpp"
#include "tests/support/sanitizers.hpp"
#include "tests/systems/cut/cut_sheet.hpp"

namespace phaco::cut {
namespace {

constexpr int kPathsPerMesh = 25;  // cut into one copy of the mesh before it is rebuilt

struct FuzzTotals {
  uint64_t paths = 0, segments = 0, samples = 0, through_rim = 0;
  uint64_t cases[kCutCases] = {};
};

class CutFuzz : public ::testing::TestWithParam<std::tuple<int, eye::CapsuleLayout, int>> {};

TEST_P(CutFuzz, RandomPathsNeverBreakTheMembrane) {
  const auto [level, layout, full_paths] = GetParam();
  // Levels 2 and 3 run a fifth of their paths under ASan (tests/support/sanitizers.hpp).
  const int paths = level >= 2 ? phaco::test::asan_scaled(full_paths, 5) : full_paths;
  const SurfaceMesh mesh =
      eye::make_capsule(eye::default_eye_params(), eye::resolution_for_level(level), layout);
  double radius = 0.0;
  for (const auto& v : mesh.vertices) radius = std::max(radius, std::hypot(v.x(), v.y()));
  // Mean edge length sets the scale of lengths and speeds.
  double edge = 0.0;
  for (const auto& t : mesh.triangles) edge += (mesh.vertices[t[0]] - mesh.vertices[t[1]]).norm();
  edge /= static_cast<double>(mesh.triangles.size());

  CutSettings settings;
  settings.snap.vertex_snap_mm = 0.1 * edge;
  settings.snap.edge_snap_mm = 0.05 * edge;
  const CounterRng rng(0xC0FFEE + 97 * level + static_cast<int>(layout), 4);
  FuzzTotals totals;
  test::CutSheet sheet;
  SpringBlocks blocks;
  SpringGraph graph;
  for (int p = 0; p < paths; ++p) {
    if (p % kPathsPerMesh == 0) {
      sheet = test::cut_sheet(mesh);
      blocks = springs::plan_blocks(sheet.springs, sheet.particles.slots.size());
      graph = springs::build_spring_graph(sheet.springs, sheet.particles.slots.size());
      sheet.topology.added_springs.clear(), sheet.topology.removed_springs.clear();
    }
    CutMesh m = sheet.mesh();
    auto u = [&](uint32_t draw) { return rng.uniform_double(static_cast<uint64_t>(p), draw, 0); };
    const int style = static_cast<int>(
        u(0) * 5);  // 0 straight, 1 through vertices, 2 along edges, 3 curving, 4 off the rim
    const double length = (0.2 + 6.0 * u(1)) * edge * (style == 4 ? 30.0 : 1.0);
    const double speed = (0.15 + 2.5 * u(2)) * edge;  // mm between samples
    const double heading = 2.0 * 3.14159265358979 * u(3);
    const double turn = style == 3 ? (u(4) - 0.5) * 2.0 / edge : 0.0;  // rad per mm
    const double r0 = radius * std::sqrt(u(5)) * 0.9;
    const double a0 = 2.0 * 3.14159265358979 * u(6);
    Vec3 x(r0 * std::cos(a0), r0 * std::sin(a0), 0.0);
    std::vector<Vec3> samples;
    if (style == 1 || style == 2) {
      // Start at a vertex and aim at another vertex (style 1) or run along a chain of edges
      // (style 2, by stepping from vertex to neighbouring vertex).
      uint32_t v =
          static_cast<uint32_t>(u(7) * sheet.particles.slots.size()) % sheet.particles.slots.size();
      for (int tries = 0; tries < 8 && !sheet.particles.slots.alive(v); ++tries)
        v = (v + 1) % sheet.particles.slots.size();
      if (!sheet.particles.slots.alive(v)) continue;
      samples.push_back(particle_position(sheet.particles, v));
      const int hops = 1 + static_cast<int>(u(8) * 6);
      std::vector<uint32_t> fan;
      for (int h = 0; h < hops; ++h) {
        const uint32_t hint = sheet.topology.vertex_triangle[v];
        if (!sheet.triangles.slots.alive(hint)) break;
        vertex_fan(sheet.triangles, sheet.topology.adjacency, hint, v, fan);
        const uint32_t t = fan[static_cast<size_t>(u(9 + h) * fan.size()) % fan.size()];
        const uint32_t next =
            corner(sheet.triangles, t, (corner_slot(sheet.triangles, t, v) + 1 + (h & 1)) % 3);
        if (style == 1) {
          samples.push_back(particle_position(sheet.particles, next));
        } else {
          const Vec3 a = particle_position(sheet.particles, v),
                     b = particle_position(sheet.particles, next);
          for (double f : {0.25, 0.5, 0.75, 1.0}) samples.push_back(a + f * (b - a));
        }
        v = next;
      }
    } else {
      double th = heading;
      samples.push_back(x);
      for (double s = speed; s <= length + 1e-12; s += speed) {
        x += speed * Vec3(std::cos(th), std::sin(th), 0.0);
        th += turn * speed;
        samples.push_back(x);
      }
    }
    CutPath path;
    EditLog log;
    for (const Vec3& q : samples) {
      // Lift the sample onto the capsule's dome so the tool point is near the surface.
      Vec3 tool = q;
      tool.z() = 5.0;
      const CutPoint c =
          locate_cut_point(sheet.particles, sheet.triangles, sheet.topology.adjacency,
                           path.hint_triangle, tool, settings.snap);
      tool = Vec3(q.x(), q.y(), c.position.z() + 0.01 * edge);
      ++totals.samples;
      const SegmentReport r = cut_towards(m, path, tool, settings, log);
      if (r.made) ++totals.segments, ++totals.cases[static_cast<int>(r.cut_case)];
      if (r.reached_boundary) break;
    }
    totals.through_rim += path.reached_boundary;
    ++totals.paths;
    const ::testing::AssertionResult ok = test::sound(sheet);
    ASSERT_TRUE(ok) << "path " << p << " (style " << style << ", " << samples.size() << " samples)";
    springs::patch_spring_graph(graph, sheet.springs, sheet.particles.slots.size(),
                                sheet.topology.removed_springs, sheet.topology.added_springs);
    sheet.topology.added_springs.clear(), sheet.topology.removed_springs.clear();
    ASSERT_EQ(topology_check::check_spring_structure(sheet.springs, blocks, graph,
                                                     sheet.particles.slots.size()),
              "")
        << "path " << p;
  }
  EXPECT_EQ(totals.paths, static_cast<uint64_t>(paths));
  EXPECT_GT(totals.segments, static_cast<uint64_t>(paths));
  EXPECT_GT(totals.through_rim, 0u);
  for (int c = 0; c < kCutCases; ++c)
    RecordProperty(std::string(to_string(static_cast<CutCase>(c))),
                   std::to_string(totals.cases[c]));
  RecordProperty("segments", std::to_string(totals.segments));
}

// 10,000 paths in all: 3,000 on each of levels 0 and 1, 2,500 on level 2 and 1,500 on level 3,
// half on the curvilinear (rings and spokes) and half on the isotropic capsule.
INSTANTIATE_TEST_SUITE_P(
    Capsule, CutFuzz,
    ::testing::Values(std::make_tuple(0, eye::CapsuleLayout::Curvilinear, 1500),
                      std::make_tuple(0, eye::CapsuleLayout::Isotropic, 1500),
                      std::make_tuple(1, eye::CapsuleLayout::Curvilinear, 1500),
                      std::make_tuple(1, eye::CapsuleLayout::Isotropic, 1500),
                      std::make_tuple(2, eye::CapsuleLayout::Curvilinear, 1250),
                      std::make_tuple(2, eye::CapsuleLayout::Isotropic, 1250),
                      std::make_tuple(3, eye::CapsuleLayout::Curvilinear, 750),
                      std::make_tuple(3, eye::CapsuleLayout::Isotropic, 750)),
    [](const auto& info) {
      return "level" + std::to_string(std::get<0>(info.param)) +
             (std::get<1>(info.param) == eye::CapsuleLayout::Curvilinear ? "_curvilinear"
                                                                         : "_isotropic");
    });

}  // namespace
}  // namespace phaco::cut
