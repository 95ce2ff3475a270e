// Seed 000 Fig. 9: grasping a membrane at a vertex, inside a triangle or on an edge (a temporary
// vertex and edges), and the release that removes them: the membrane stays sound throughout and a
// release gives back exactly the triangles, springs and masses the grasp found; a cut through the
// temporary vertex keeps it; momentum is handed on; 2,000 random grasps among random cuts.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

#include "engine/core/rng.hpp"
#include "procedures/eye/eye_mesh.hpp"
#include "procedures/eye/eye_params.hpp"
#include "procedures/eye/resolution.hpp"
#include "systems/cut/grasp_point.hpp"
#include "tests/support/grid_mesh.hpp"
#include "tests/support/sanitizers.hpp"
#include "tests/systems/cut/cut_sheet.hpp"

namespace phaco::cut {
namespace {

using test::CutSheet;
using test::sound;

// A sheet whose springs and masses are all what refresh_region gives (the values a release
// restores), and its mean edge length.
CutSheet prepared(const SurfaceMesh& mesh) {
  CutSheet s = test::cut_sheet(mesh);
  EditLog all;
  for (uint32_t t = 0; t < s.triangles.slots.size(); ++t)
    if (s.triangles.slots.alive(t)) all.touched_triangles.push_back(t);
  CutMesh m = s.mesh();
  refresh_region(m, all);
  return s;
}

double mean_edge(const CutSheet& s) {
  double sum = 0.0;
  uint32_t n = 0;
  for (uint32_t e = 0; e < s.springs.slots.size(); ++e)
    if (s.springs.slots.alive(e))
      sum += (particle_position(s.particles, s.springs.i[e]) -
              particle_position(s.particles, s.springs.j[e]))
                 .norm(),
          ++n;
  return sum / n;
}

CutSettings settings_for(double edge) {
  CutSettings s;
  s.snap.vertex_snap_mm = 0.1 * edge;
  s.snap.edge_snap_mm = 0.05 * edge;
  return s;
}

// The membrane as sets (sorted): triangles as corner triples rotated to start at the lowest
// (orientation kept), the edges across which triangles are linked (once per side), springs by
// pair, particles by index.
struct Snapshot {
  std::vector<std::array<uint32_t, 3>> triangles;
  std::vector<std::pair<uint32_t, uint32_t>> linked;
  std::vector<std::tuple<uint32_t, uint32_t, double, double>>
      springs;  // i, j, rest length, stiffness
  std::vector<std::pair<uint32_t, std::array<double, 4>>>
      particles;  // index; x, y, z, inverse mass
};

Snapshot snapshot(const CutSheet& s) {
  Snapshot out;
  for (uint32_t t = 0; t < s.triangles.slots.size(); ++t) {
    if (!s.triangles.slots.alive(t)) continue;
    std::array<uint32_t, 3> c{s.triangles.a[t], s.triangles.b[t], s.triangles.c[t]};
    while (c[0] > c[1] || c[0] > c[2]) c = {c[1], c[2], c[0]};
    out.triangles.push_back(c);
    for (int k = 0; k < 3; ++k)
      if (s.topology.adjacency.neighbour[t][k] != kInvalidIndex)
        out.linked.push_back(
            std::minmax(corner(s.triangles, t, k), corner(s.triangles, t, (k + 1) % 3)));
  }
  for (uint32_t e = 0; e < s.springs.slots.size(); ++e)
    if (s.springs.slots.alive(e))
      out.springs.emplace_back(s.springs.i[e], s.springs.j[e], s.springs.rest_length[e],
                               s.springs.stiffness[e]);
  for (uint32_t v = 0; v < s.particles.slots.size(); ++v)
    if (s.particles.slots.alive(v))
      out.particles.push_back(
          {v, {s.particles.x[v], s.particles.y[v], s.particles.z[v], s.particles.inv_mass[v]}});
  std::sort(out.triangles.begin(), out.triangles.end());
  std::sort(out.linked.begin(), out.linked.end());
  std::sort(out.springs.begin(), out.springs.end());
  return out;
}

bool close(double x, double y) {
  return std::abs(x - y) <= 1e-6 * std::max({std::abs(x), std::abs(y), 1e-30});
}

::testing::AssertionResult same(const Snapshot& before, const Snapshot& after) {
  if (before.triangles != after.triangles)
    return ::testing::AssertionFailure() << "the triangle sets differ";
  if (before.linked != after.linked)
    return ::testing::AssertionFailure() << "the triangle adjacency differs";
  if (before.springs.size() != after.springs.size() ||
      before.particles.size() != after.particles.size())
    return ::testing::AssertionFailure() << "spring or particle counts differ";
  for (size_t k = 0; k < before.springs.size(); ++k) {
    const auto& [i, j, rest, stiffness] = before.springs[k];
    const auto& [i2, j2, rest2, stiffness2] = after.springs[k];
    if (i != i2 || j != j2)
      return ::testing::AssertionFailure() << "spring " << i << "-" << j << " is gone";
    if (!close(rest, rest2) || !close(stiffness, stiffness2))
      return ::testing::AssertionFailure()
             << "spring " << i << "-" << j << ": rest " << rest << " -> " << rest2 << ", stiffness "
             << stiffness << " -> " << stiffness2;
  }
  for (size_t k = 0; k < before.particles.size(); ++k) {
    const auto& [v, x] = before.particles[k];
    const auto& [v2, x2] = after.particles[k];
    if (v != v2) return ::testing::AssertionFailure() << "particle " << v << " is gone";
    for (int c = 0; c < 4; ++c)
      if (!close(x[c], x2[c]))
        return ::testing::AssertionFailure()
               << "particle " << v << " column " << c << ": " << x[c] << " -> " << x2[c];
  }
  return ::testing::AssertionSuccess();
}

// The interior vertex nearest the mesh's centroid.
uint32_t central_vertex(const CutSheet& s) {
  Vec3 centre = Vec3::Zero();
  for (uint32_t v = 0; v < s.particles.slots.size(); ++v)
    centre += particle_position(s.particles, v);
  centre /= s.particles.slots.size();
  CutSheet& w = const_cast<CutSheet&>(s);
  const CutMesh m = w.mesh();
  uint32_t best = kInvalidIndex;
  double bd = 1e300;
  for (uint32_t v = 0; v < s.particles.slots.size(); ++v) {
    const double d = (particle_position(s.particles, v) - centre).norm();
    if (d < bd && !on_boundary(m, v)) bd = d, best = v;
  }
  return best;
}

struct MeshCase {
  const char* name;
  int level;  // -1: a 6 × 6 unit grid with jittered interior
};

SurfaceMesh mesh_of(const MeshCase& c) {
  if (c.level < 0) return phaco::test::grid_mesh(6, 0.15);
  return eye::make_capsule(eye::default_eye_params(), eye::resolution_for_level(c.level),
                           eye::CapsuleLayout::Curvilinear);
}

class GraspRelease : public ::testing::TestWithParam<std::tuple<MeshCase, CutPoint::Kind>> {};

TEST_P(GraspRelease, RestoresTheMembraneExactly) {
  const auto [mc, kind] = GetParam();
  CutSheet s = prepared(mesh_of(mc));
  const CutSettings settings = settings_for(mean_edge(s));
  const Snapshot before = snapshot(s);
  // A point of the wanted kind next to the central vertex v: v itself, 0.4 of the way along an
  // edge from v, or the centroid of a triangle around v.
  const uint32_t v = central_vertex(s);
  const uint32_t T = s.topology.vertex_triangle[v];
  const uint32_t n = corner(s.triangles, T, (corner_slot(s.triangles, T, v) + 1) % 3);
  const Vec3 xv = particle_position(s.particles, v), xn = particle_position(s.particles, n);
  Vec3 target = xv;
  if (kind == CutPoint::Edge) target = 0.6 * xv + 0.4 * xn;
  if (kind == CutPoint::Face)
    target = (xv + xn +
              particle_position(s.particles,
                                corner(s.triangles, T, (corner_slot(s.triangles, T, v) + 2) % 3))) /
             3.0;
  const CutPoint where =
      locate_cut_point(s.particles, s.triangles, s.topology.adjacency, T, target, settings.snap);
  ASSERT_EQ(where.kind, kind);

  CutMesh m = s.mesh();
  EditLog log;
  const uint32_t np = s.particles.slots.live_count(), nt = s.triangles.slots.live_count(),
                 ns = s.springs.slots.live_count();
  GraspPoint g = grasp_at(m, where, settings, log);
  ASSERT_TRUE(g.held());
  EXPECT_EQ(g.kind, kind);
  EXPECT_EQ(g.temporary, kind != CutPoint::Vertex);
  EXPECT_LT((particle_position(s.particles, g.particle) - target).norm(), 1e-5);
  const uint32_t added = kind == CutPoint::Vertex ? 0 : 1;
  EXPECT_EQ(s.particles.slots.live_count(), np + added);
  EXPECT_EQ(s.triangles.slots.live_count(), nt + 2 * added);  // 1 -> 3 or 2 -> 4
  EXPECT_EQ(s.springs.slots.live_count(), ns + (kind == CutPoint::Face   ? 3
                                                : kind == CutPoint::Edge ? 3
                                                                         : 0));  // edge: -1 + 4
  EXPECT_TRUE(sound(s)) << mc.name;
  if (g.temporary) {
    EXPECT_GT(s.particles.inv_mass[g.particle],
              0.0f);  // a real mass point for the forces to act on
    EXPECT_FALSE(same(before, snapshot(s)));
  }
  const uint32_t held = g.particle;
  const ReleaseReport r = release(m, g, log);
  EXPECT_TRUE(r.released);
  EXPECT_EQ(r.removed_temporary, kind != CutPoint::Vertex);
  EXPECT_FALSE(r.kept_temporary);
  EXPECT_FALSE(g.held());
  EXPECT_EQ(s.particles.slots.alive(held), kind == CutPoint::Vertex);
  EXPECT_TRUE(sound(s)) << mc.name;
  EXPECT_TRUE(same(before, snapshot(s))) << mc.name;
}

INSTANTIATE_TEST_SUITE_P(
    Meshes, GraspRelease,
    ::testing::Combine(::testing::Values(MeshCase{"grid", -1}, MeshCase{"capsule0", 0},
                                         MeshCase{"capsule1", 1}, MeshCase{"capsule2", 2}),
                       ::testing::Values(CutPoint::Vertex, CutPoint::Face, CutPoint::Edge)),
    [](const auto& info) {
      const CutPoint::Kind k = std::get<1>(info.param);
      return std::string(std::get<0>(info.param).name) + (k == CutPoint::Vertex ? "_vertex"
                                                          : k == CutPoint::Face ? "_face"
                                                                                : "_edge");
    });

Vec3 grasp_at(double x, double y) {
  return {x, y, 0.0};
}

TEST(GraspPoint, OnARimEdgeSplitsItsOneTriangle) {
  CutSheet s = prepared(phaco::test::grid_mesh(5, 0.0));
  const Snapshot before = snapshot(s);
  CutMesh m = s.mesh();
  EditLog log;
  const CutSettings settings = settings_for(1.0);
  GraspPoint g = grasp_near(m, grasp_at(1.5, 0.0), 0, settings, log);
  ASSERT_TRUE(g.held());
  EXPECT_EQ(g.kind, CutPoint::Edge);
  EXPECT_EQ(g.insertion.original_count, 1u);
  EXPECT_EQ(g.insertion.piece_count, 2u);
  EXPECT_EQ(s.triangles.slots.live_count(), 32u + 1u);
  EXPECT_EQ(s.springs.slots.live_count(), before.springs.size() + 2u);
  EXPECT_TRUE(on_boundary(m, g.particle));
  EXPECT_TRUE(sound(s));
  const ReleaseReport r = release(m, g, log);
  EXPECT_TRUE(r.removed_temporary);
  EXPECT_TRUE(sound(s));
  EXPECT_TRUE(same(before, snapshot(s)));
}

TEST(GraspPoint, ACutThroughTheTemporaryVertexKeepsIt) {
  CutSheet s = prepared(phaco::test::grid_mesh(7, 0.0));
  CutMesh m = s.mesh();
  EditLog log;
  const CutSettings settings = settings_for(1.0);
  GraspPoint g = grasp_near(m, grasp_at(2.3, 2.6), 0, settings, log);
  ASSERT_TRUE(g.held());
  ASSERT_EQ(g.kind, CutPoint::Face);
  const uint32_t q = g.particle;
  CutPath path;
  for (const Vec3& x : {grasp_at(0.6, 2.6), grasp_at(2.3, 2.6), grasp_at(4.4, 2.6)})
    cut_towards(m, path, x, settings, log);
  ASSERT_GE(path.segments, 1u);
  EXPECT_EQ(insertion_state(m, g.insertion), InsertionState::Changed);
  EXPECT_TRUE(sound(s));
  const ReleaseReport r = release(m, g, log);
  EXPECT_TRUE(r.released);
  EXPECT_FALSE(r.removed_temporary);
  EXPECT_TRUE(r.kept_temporary);
  EXPECT_EQ(r.state, InsertionState::Changed);
  EXPECT_TRUE(s.particles.slots.alive(q));
  EXPECT_TRUE(sound(s));
}

TEST(GraspPoint, ACutElsewhereDoesNotStopTheRelease) {
  CutSheet s = prepared(phaco::test::grid_mesh(7, 0.0));
  CutMesh m = s.mesh();
  EditLog log;
  const CutSettings settings = settings_for(1.0);
  GraspPoint g = grasp_near(m, grasp_at(2.3, 2.6), 0, settings, log);
  ASSERT_TRUE(g.temporary);
  CutPath path;
  for (const Vec3& x : {grasp_at(0.6, 4.5), grasp_at(2.3, 4.5), grasp_at(4.4, 4.5)})
    cut_towards(m, path, x, settings, log);
  ASSERT_GE(path.segments, 1u);
  EXPECT_EQ(insertion_state(m, g.insertion), InsertionState::Intact);
  const Snapshot cut = snapshot(s);
  const ReleaseReport r = release(m, g, log);
  EXPECT_TRUE(r.removed_temporary);
  EXPECT_TRUE(sound(s));
  EXPECT_EQ(snapshot(s).triangles.size() + 2, cut.triangles.size());
}

// Two forceps: the second grasps an edge through the first's temporary vertex. Released last in,
// first out, both go and the membrane is as it was; the other way round, the first is kept.
TEST(GraspPoint, NestedGraspsReleaseLastInFirstOut) {
  for (const bool lifo : {true, false}) {
    CutSheet s = prepared(phaco::test::grid_mesh(6, 0.15));
    const Snapshot before = snapshot(s);
    CutMesh m = s.mesh();
    EditLog log;
    const CutSettings settings = settings_for(1.0);
    const uint32_t T = s.topology.vertex_triangle[central_vertex(s)];
    Vec3 centroid = Vec3::Zero();
    for (int k = 0; k < 3; ++k)
      centroid += particle_position(s.particles, corner(s.triangles, T, k)) / 3.0;
    GraspPoint first = grasp_near(m, centroid, T, settings, log);
    ASSERT_EQ(first.kind, CutPoint::Face);
    const uint32_t q = first.particle, a = first.insertion.original_corners[0][0];
    const Vec3 mid = 0.5 * (particle_position(s.particles, q) + particle_position(s.particles, a));
    GraspPoint second = grasp_near(m, mid, s.topology.vertex_triangle[q], settings, log);
    ASSERT_EQ(second.kind, CutPoint::Edge);
    EXPECT_EQ(insertion_state(m, first.insertion), InsertionState::Changed);
    EXPECT_TRUE(sound(s));
    if (lifo) {
      EXPECT_TRUE(release(m, second, log).removed_temporary);
      EXPECT_TRUE(release(m, first, log).removed_temporary);
      EXPECT_TRUE(same(before, snapshot(s)));
    } else {
      EXPECT_TRUE(release(m, first, log).kept_temporary);
      EXPECT_TRUE(release(m, second, log).removed_temporary);
      EXPECT_TRUE(s.particles.slots.alive(q));
    }
    EXPECT_TRUE(sound(s)) << (lifo ? "last in, first out" : "first in, first out");
  }
}

TEST(GraspPoint, ReleaseHandsOnTheVertexMomentum) {
  CutSheet s = prepared(phaco::test::grid_mesh(6, 0.15));
  CutMesh m = s.mesh();
  EditLog log;
  GraspPoint g = grasp_near(m, grasp_at(2.35, 2.62), 0, settings_for(1.0), log);
  ASSERT_TRUE(g.temporary);
  Particles& p = s.particles;
  for (uint32_t v = 0; v < p.slots.size(); ++v) {
    if (!p.slots.alive(v)) continue;
    p.vx[v] = static_cast<float>(std::sin(1.0 + v)),
    p.vy[v] = static_cast<float>(std::cos(2.0 * v));
    p.vz[v] = static_cast<float>(0.5 * std::sin(3.0 * v));
  }
  p.vx[g.particle] = 30.0f, p.vy[g.particle] = -20.0f, p.vz[g.particle] = 50.0f;
  p.z[g.particle] = 0.3f;  // pulled up by the forceps
  const auto totals = [&](Vec3& momentum, double& mass) {
    momentum.setZero(), mass = 0.0;
    for (uint32_t v = 0; v < p.slots.size(); ++v)
      if (p.slots.alive(v) && p.inv_mass[v] > 0)
        momentum += Vec3(p.vx[v], p.vy[v], p.vz[v]) / p.inv_mass[v], mass += 1.0 / p.inv_mass[v];
  };
  Vec3 m0, m1;
  double mass0 = 0, mass1 = 0;
  totals(m0, mass0);
  const Vec3 vq = Vec3(30, -20, 50) / p.inv_mass[g.particle];
  ASSERT_GT(vq.norm(), 0.05 * m0.norm());  // the vertex's share is not negligible
  const ReleaseReport r = release(m, g, log);
  ASSERT_TRUE(r.removed_temporary);
  totals(m1, mass1);
  EXPECT_LT((m1 - m0).norm(), 1e-5 * m0.norm()) << m0.transpose() << " -> " << m1.transpose();
  EXPECT_NEAR(mass1, mass0, 1e-6 * mass0);
  EXPECT_TRUE(sound(s));
}

TEST(GraspPoint, QualitySnapMovesASliverSplitToTheEdge) {
  CutSheet s = prepared(phaco::test::grid_mesh(5, 0.0));
  CutMesh m = s.mesh();
  EditLog log;
  // 0.02 from the edge y = 1 (beyond the 0.01 edge snap): a face split would leave a 2.3° angle.
  CutSettings settings = settings_for(1.0);
  settings.snap.edge_snap_mm = 0.01;
  GraspPoint g = grasp_near(m, grasp_at(1.5, 1.02), 0, settings, log);
  ASSERT_TRUE(g.held());
  EXPECT_EQ(g.kind, CutPoint::Edge);
  EXPECT_NEAR(g.moved_mm, 0.02, 1e-6);
  EXPECT_TRUE(sound(s));
  settings.min_angle_deg = 1.0;  // the split is allowed
  release(m, g, log);
  g = grasp_near(m, grasp_at(1.5, 1.02), 0, settings, log);
  EXPECT_EQ(g.kind, CutPoint::Face);
  EXPECT_TRUE(sound(s));
}

TEST(GraspPoint, AnchoredTissueIsNotGrasped) {
  CutSheet s = prepared(phaco::test::grid_mesh(5, 0.0));
  for (uint32_t v : {0u, 1u, 2u, 3u, 4u, 6u})
    s.particles.kind[v] = ParticleKind::Anchored, s.particles.inv_mass[v] = 0.0f;
  CutMesh m = s.mesh();
  EditLog log;
  const uint32_t np = s.particles.slots.live_count();
  EXPECT_FALSE(grasp_near(m, grasp_at(1.0, 1.0), 0, settings_for(1.0), log).held());  // vertex 6
  EXPECT_FALSE(
      grasp_near(m, grasp_at(1.5, 0.0), 0, settings_for(1.0), log).held());  // rim edge 1-2
  EXPECT_EQ(s.particles.slots.live_count(), np);
  EXPECT_TRUE(grasp_near(m, grasp_at(1.5, 1.5), 0, settings_for(1.0), log)
                  .held());  // a triangle with a free corner
}

TEST(GraspPoint, StaleGraspPointIsRejected) {
  CutSheet s = prepared(phaco::test::grid_mesh(4, 0.0));
  CutMesh m = s.mesh();
  EditLog log;
  CutPoint where;
  where.kind = CutPoint::Face;
  where.triangle = 1000;
  EXPECT_THROW(grasp_at(m, where, settings_for(1.0), log), std::invalid_argument);
}

// 2,000 grasp/release pairs at random points (vertices, edges, insides) of the level-1 curvilinear
// and level-0 isotropic capsules, with random short cuts (half of them starting at the grasp point)
// and forceps pulls between grasp and release; the mesh is rebuilt every 40 pairs.
TEST(GraspPoint, FuzzAmongCuts) {
  // Half the pairs under ASan (tests/support/sanitizers.hpp); the thresholds below scale with them.
  constexpr int kPairs = phaco::test::asan_scaled(2000, 2), kPerSheet = 40;
  const CounterRng rng(0x6A5B, 9);
  int removed = 0, kept = 0, at_vertex = 0, exact = 0;
  for (int layout = 0; layout < 2; ++layout) {
    const SurfaceMesh mesh = eye::make_capsule(
        eye::default_eye_params(), eye::resolution_for_level(1 - layout),
        layout == 0 ? eye::CapsuleLayout::Curvilinear : eye::CapsuleLayout::Isotropic);
    CutSheet s;
    CutSettings settings;
    double edge = 1.0;
    for (int i = 0; i < kPairs / 2; ++i) {
      const uint64_t id = static_cast<uint64_t>(layout * kPairs + i);
      const auto u = [&](uint32_t draw) { return rng.uniform_double(id, draw, 0); };
      if (i % kPerSheet == 0) {
        s = prepared(mesh);
        edge = mean_edge(s);
        settings = settings_for(edge);
      }
      CutMesh m = s.mesh();
      uint32_t T =
          static_cast<uint32_t>(u(0) * s.triangles.slots.size()) % s.triangles.slots.size();
      while (!s.triangles.slots.alive(T)) T = (T + 1) % s.triangles.slots.size();
      const int style = static_cast<int>(u(1) * 3);  // 0 corner, 1 edge, 2 inside
      Vec3 w(u(2), u(3), u(4));
      if (style == 0) w = Vec3::Unit(static_cast<int>(u(5) * 3) % 3);
      if (style == 1) w[static_cast<int>(u(5) * 3) % 3] = 0.0;
      w /= w.sum();
      Vec3 target = Vec3::Zero();
      for (int k = 0; k < 3; ++k)
        target += w[k] * particle_position(s.particles, corner(s.triangles, T, k));
      const CutPoint where = locate_cut_point(s.particles, s.triangles, s.topology.adjacency, T,
                                              target, settings.snap);
      const bool cut = u(6) < 0.4, pull = u(7) < 0.3;
      const Snapshot before = cut ? Snapshot{} : snapshot(s);
      EditLog log;
      GraspPoint g = grasp_at(m, where, settings, log);
      ASSERT_TRUE(sound(s)) << "grasp " << id;
      if (!g.held()) continue;
      at_vertex += !g.temporary;
      const uint32_t q = g.particle;
      const bool temporary = g.temporary;
      if (cut) {
        const Vec3 start = u(8) < 0.5 ? particle_position(s.particles, q) : target;
        const double heading = 6.283185307179586 * u(9), step = (0.4 + 1.2 * u(10)) * edge;
        const int samples = 2 + static_cast<int>(u(11) * 3);
        CutPath path;
        for (int k = 0; k < samples; ++k) {
          Vec3 x = start + k * step * Vec3(std::cos(heading), std::sin(heading), 0.0);
          x.z() = 5.0;
          const CutPoint c =
              locate_cut_point(s.particles, s.triangles, s.topology.adjacency, T, x, settings.snap);
          x.z() = c.position.z() + 0.01 * edge;
          if (k == 0 && u(8) < 0.5) x = particle_position(s.particles, q);
          if (cut_towards(m, path, x, settings, log).reached_boundary) break;
        }
        ASSERT_TRUE(sound(s)) << "cut " << id;
      }
      const float z_held = s.particles.slots.alive(q) ? s.particles.z[q] : 0.0f;
      if (pull && s.particles.slots.alive(q)) {
        s.particles.z[q] += static_cast<float>(0.3 * edge * u(12));
        s.particles.vz[q] = static_cast<float>(10.0 * u(13));
      }
      const ReleaseReport r = release(m, g, log);
      ASSERT_TRUE(sound(s)) << "release " << id;
      removed += r.removed_temporary;
      kept += r.kept_temporary;
      if (!cut) {
        // Nothing but the grasp (and a pull of the temporary vertex) happened: all is as before.
        ASSERT_EQ(r.removed_temporary, temporary) << id;
        if (s.particles.slots.alive(q)) s.particles.vz[q] = 0.0f, s.particles.z[q] = z_held;
        ASSERT_TRUE(same(before, snapshot(s))) << "pair " << id;
        ++exact;
      }
    }
  }
  RecordProperty("removed", removed);
  RecordProperty("kept", kept);
  EXPECT_GT(removed, kPairs / 3);
  EXPECT_GT(kept, kPairs / 40);
  EXPECT_GT(at_vertex, kPairs / 40);
  EXPECT_GT(exact, kPairs / 3);
}

}  // namespace
}  // namespace phaco::cut
