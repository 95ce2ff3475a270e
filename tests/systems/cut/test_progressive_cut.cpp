// Seed 000 §5.2 progressive cutting: Table 1's canonical cases, segments over one, two and many
// triangles, the duplication of c_t, split springs, pre-stretch opening the cut, remeshing and the
// cut edge's distance to the tool path.
#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>
#include <utility>
#include <vector>

#include "tests/support/grid_mesh.hpp"
#include "tests/systems/cut/cut_sheet.hpp"

namespace phaco::cut {
namespace {

using test::cut_sheet;
using test::CutSheet;
using test::sound;

CutSettings settings() {
  CutSettings s;
  s.snap.vertex_snap_mm = 0.02;
  s.snap.edge_snap_mm = 0.01;
  s.min_angle_deg = 5.0;
  return s;
}

Vec3 P(double x, double y) {
  return {x, y, 0.0};
}

// The live particle nearest to x (and its distance).
uint32_t nearest(const CutSheet& s, const Vec3& x, double* d = nullptr) {
  uint32_t best = kInvalidIndex;
  double bd = 1e300;
  for (uint32_t v = 0; v < s.particles.slots.size(); ++v) {
    if (!s.particles.slots.alive(v)) continue;
    const double dv = (particle_position(s.particles, v) - x).norm();
    if (dv < bd) bd = dv, best = v;
  }
  if (d) *d = bd;
  return best;
}

struct CanonicalCase {
  const char* name;
  Vec3 from, to;
  CutCase expected;
  uint32_t new_points;  // inserted cut points
  uint32_t spanned;
  uint32_t copies;  // the path's inner vertices, one copy each; its two ends are crack tips
};

class Canonical : public ::testing::TestWithParam<CanonicalCase> {};

// Quad (1, 1) of the 5 × 5 unit grid is split along (1,1)-(2,2); its lower triangle is
// (1,1), (2,1), (2,2).
TEST_P(Canonical, InitialCutMakesTheCaseTheTableNames) {
  const CanonicalCase c = GetParam();
  CutSheet s = cut_sheet(phaco::test::grid_mesh(5, 0.0));
  CutMesh m = s.mesh();
  CutPath path;
  EditLog log;
  const uint32_t particles_before = s.particles.slots.live_count();
  EXPECT_FALSE(cut_towards(m, path, c.from, settings(), log).made);  // c_0 only
  const SegmentReport r = cut_towards(m, path, c.to, settings(), log);
  ASSERT_TRUE(r.made) << c.name;
  EXPECT_EQ(r.cut_case, c.expected) << c.name << " gave " << to_string(r.cut_case);
  EXPECT_EQ(r.triangles_spanned, c.spanned) << c.name;
  EXPECT_EQ(log.edge_splits + log.face_splits, c.new_points) << c.name;
  EXPECT_EQ(log.duplicated_vertices, c.copies) << c.name;
  EXPECT_EQ(s.particles.slots.live_count(), particles_before + c.new_points);
  // The cut's ends are mesh vertices where the tool put them.
  double d0 = 0, d1 = 0;
  nearest(s, c.from, &d0);
  nearest(s, c.to, &d1);
  EXPECT_LT(d0, 1e-6) << c.name;
  EXPECT_LT(d1, 1e-6) << c.name;
  EXPECT_LT((particle_position(s.particles, path.tip) - c.to).norm(), 1e-6) << c.name;
  EXPECT_TRUE(sound(s)) << c.name;
}

INSTANTIATE_TEST_SUITE_P(
    Table1, Canonical,
    ::testing::Values(
        CanonicalCase{"face-face", P(1.55, 1.2), P(1.85, 1.5), CutCase::IC1, 2, 1, 0},
        CanonicalCase{"edge-edge", P(1.5, 1.0), P(1.6, 1.6), CutCase::IC2, 2, 1, 0},
        CanonicalCase{"vertex-vertex along an edge", P(1, 1), P(2, 2), CutCase::IC3, 0, 1, 0},
        CanonicalCase{"vertex-vertex across two", P(1, 2), P(2, 1), CutCase::IC3, 1, 2, 1},
        CanonicalCase{"face-edge", P(1.6, 1.3), P(2.0, 1.5), CutCase::IC4, 2, 1, 0},
        CanonicalCase{"edge-face", P(2.0, 1.5), P(1.7, 1.25), CutCase::IC4, 2, 1, 0},
        CanonicalCase{"face-vertex", P(1.6, 1.3), P(2, 1), CutCase::IC5, 1, 1, 0},
        CanonicalCase{"vertex-face", P(2, 1), P(1.6, 1.3), CutCase::IC5, 1, 1, 0},
        CanonicalCase{"edge-vertex", P(1.5, 1.0), P(2, 2), CutCase::IC6, 1, 1, 0},
        CanonicalCase{"face-face across two", P(1.7, 1.2), P(1.2, 1.6), CutCase::IC1, 3, 2, 1}),
    [](const auto& info) {
      std::string n = info.param.name;
      for (char& ch : n)
        if (ch == ' ' || ch == '-') ch = '_';
      return n;
    });

// Boundary edges that are not on the n × n grid's outer rim: the two lips of every cut edge.
std::vector<std::pair<Vec3, Vec3>> cut_lip_edges(const CutSheet& s, double n) {
  std::vector<std::pair<Vec3, Vec3>> out;
  for (uint32_t t = 0; t < s.triangles.slots.size(); ++t) {
    if (!s.triangles.slots.alive(t)) continue;
    for (int k = 0; k < 3; ++k) {
      if (s.topology.adjacency.neighbour[t][k] != kInvalidIndex) continue;
      const Vec3 u = particle_position(s.particles, corner(s.triangles, t, k)),
                 w = particle_position(s.particles, corner(s.triangles, t, (k + 1) % 3));
      bool rim = false;
      for (int axis = 0; axis < 2; ++axis)
        for (double side : {0.0, n - 1}) rim = rim || (u[axis] == side && w[axis] == side);
      if (!rim) out.emplace_back(u, w);
    }
  }
  return out;
}

uint32_t cut_boundary_edges(const CutSheet& s, double n) {
  return static_cast<uint32_t>(cut_lip_edges(s, n).size());
}

TEST(ProgressiveCut, SubsequentCutsDuplicateTheCurrentCutPointAndSplitItsSprings) {
  CutSheet s = cut_sheet(phaco::test::grid_mesh(6, 0.0));
  CutMesh m = s.mesh();
  CutSettings cs = settings();
  cs.remesh = false;  // so every path vertex stays, one per lip
  CutPath path;
  EditLog log;
  cut_towards(m, path, P(1.6, 1.3), cs, log);
  ASSERT_EQ(cut_towards(m, path, P(2.0, 1.5), cs, log).cut_case, CutCase::IC4);
  const uint32_t ct = path.tip;
  const Vec3 ct_pos = particle_position(s.particles, ct);
  EXPECT_EQ(log.duplicated_vertices, 0u);
  // A one-edge slit: two lips, but both ends are tips shared by them, so it cannot gape yet.
  EXPECT_EQ(cut_boundary_edges(s, 6), 2u);

  // SC1 into the face beyond: c_t now has cuts on both sides and is duplicated into c_t'.
  const SegmentReport sc1 = cut_towards(m, path, P(2.25, 1.55), cs, log);
  EXPECT_EQ(sc1.cut_case, CutCase::SC1);
  EXPECT_EQ(log.duplicated_vertices, 1u);
  uint32_t copies = 0;
  for (uint32_t v : log.new_particles)
    copies += v != ct && (particle_position(s.particles, v) - ct_pos).norm() < 1e-9;
  EXPECT_EQ(copies, 1u) << "c_t' is an identical copy of c_t";
  EXPECT_EQ(cut_boundary_edges(s, 6), 4u) << "two path edges, two lips each";
  EXPECT_TRUE(sound(s));

  // SC2 to an edge and SC3 to a vertex.
  EXPECT_EQ(cut_towards(m, path, P(2.6, 1.0), cs, log).cut_case, CutCase::SC2);
  EXPECT_TRUE(sound(s));
  EXPECT_EQ(cut_towards(m, path, P(3.0, 2.0), cs, log).cut_case, CutCase::SC3);
  EXPECT_TRUE(sound(s));
  // Every inner path vertex exists twice, one per lip; the two ends stay single (crack tips).
  const uint32_t lips = cut_boundary_edges(s, 6);
  EXPECT_EQ(lips % 2, 0u);
  EXPECT_EQ(log.duplicated_vertices, lips / 2 - 1);
  EXPECT_EQ(path.case_counts[static_cast<int>(CutCase::SC1)], 1u);
  EXPECT_EQ(path.case_counts[static_cast<int>(CutCase::SC2)], 1u);
  EXPECT_EQ(path.case_counts[static_cast<int>(CutCase::SC3)], 1u);
}

TEST(ProgressiveCut, LongSegmentsAreDecomposedIntoOneTriangleSteps) {
  for (double spacing : {0.3, 1.7}) {
    CutSheet s = cut_sheet(phaco::test::grid_mesh(12, 0.2));
    CutMesh m = s.mesh();
    CutPath path;
    EditLog log;
    const Vec3 a = P(1.3, 1.2), b = P(9.7, 8.1);
    const int n = static_cast<int>(std::ceil((b - a).norm() / spacing));
    for (int k = 0; k <= n; ++k) {
      cut_towards(m, path, a + (b - a) * (static_cast<double>(k) / n), settings(), log);
      ASSERT_TRUE(sound(s)) << "after sample " << k << " at spacing " << spacing;
    }
    EXPECT_FALSE(path.reached_boundary);
    EXPECT_LT((particle_position(s.particles, path.tip) - b).norm(), 0.05);
    if (spacing > 1.0) {
      EXPECT_GT(path.span_counts[3], 0u) << "segments over three or more triangles";
    } else {
      EXPECT_GT(path.span_counts[1] + path.span_counts[2], 0u);
    }
  }
}

TEST(ProgressiveCut, ACutReachingTheRimSeparatesItAndEndsThePath) {
  CutSheet s = cut_sheet(phaco::test::grid_mesh(6, 0.1));
  CutMesh m = s.mesh();
  CutPath path;
  EditLog log;
  cut_towards(m, path, P(2.4, 2.3), settings(), log);
  for (double x = 2.0; x > -0.5; x -= 0.4)
    cut_towards(m, path, P(x, 2.3 + 0.1 * (2.4 - x)), settings(), log);
  EXPECT_TRUE(path.reached_boundary);
  EXPECT_TRUE(sound(s));
  const uint32_t live = s.particles.slots.live_count();
  EXPECT_TRUE(cut_towards(m, path, P(3.5, 3.5), settings(), log).reached_boundary)
      << "ignored until end_cut";
  EXPECT_EQ(s.particles.slots.live_count(), live);
  end_cut(path);
  cut_towards(m, path, P(3.3, 3.4), settings(), log);
  EXPECT_TRUE(cut_towards(m, path, P(3.8, 3.7), settings(), log).made) << "a new initial cut";
  EXPECT_TRUE(sound(s));
}

// A tremor swings the blade back beside its own slit. With CutSettings::slit_mm the blade slides
// in the slit and cuts on once it is ahead of the tip again; without it, the path cuts a sliver
// beside its own slit.
TEST(ProgressiveCut, ABladeSwingingBackInItsSlitCutsNothing) {
  for (const double slit : {0.0, 0.1}) {
    CutSheet s = cut_sheet(phaco::test::grid_mesh(12, 0.0));
    CutMesh m = s.mesh();
    CutPath path;
    EditLog log;
    CutSettings cs = settings();
    cs.slit_mm = slit;
    for (double x = 2.0; x <= 6.01; x += 0.25) cut_towards(m, path, P(x, 5.0), cs, log);
    ASSERT_TRUE(sound(s));
    const uint32_t live = s.particles.slots.live_count(), segments = path.segments;
    bool made = false;
    for (const Vec3& back : {P(5.75, 5.07), P(5.5, 5.08), P(5.6, 4.93)})
      made = cut_towards(m, path, back, cs, log).made || made;
    EXPECT_TRUE(sound(s));
    const uint32_t after_swing = s.particles.slots.live_count();
    // Ahead of the tip again: with the rule the blade cuts on from where the slit ends; without it
    // the path's tip has moved down the sliver, and the way ahead lies across its own lip.
    const bool on = cut_towards(m, path, P(6.5, 5.0), cs, log).made;
    EXPECT_TRUE(sound(s));
    if (slit > 0) {
      EXPECT_FALSE(made) << "slid in the slit";
      EXPECT_EQ(after_swing, live);
      EXPECT_EQ(path.segments, segments + 1);
      EXPECT_TRUE(on);
    } else {
      EXPECT_TRUE(made) << "without the rule the swing cuts beside the slit";
      EXPECT_FALSE(on);
    }
  }
}

TEST(ProgressiveCut, PrestretchedSpringsPullTheLipsApart) {
  CutSheet s = cut_sheet(phaco::test::grid_mesh(10, 0.15), 0.05, springs::Pretension::Cotangent);
  CutMesh m = s.mesh();
  CutPath path;
  EditLog log;
  const Vec3 a = P(2.2, 4.6), b = P(7.3, 5.1);
  for (int k = 0; k <= 20; ++k) cut_towards(m, path, a + (b - a) * (k / 20.0), settings(), log);
  ASSERT_TRUE(sound(s));
  // Net spring force on each lip vertex (not the two tips): it must point into the vertex's own
  // side, i.e. away from the cut, so the incision gapes.
  std::vector<Vec3> force(s.particles.slots.size(), Vec3::Zero());
  for (uint32_t e = 0; e < s.springs.slots.size(); ++e) {
    if (!s.springs.slots.alive(e)) continue;
    const Vec3 d = particle_position(s.particles, s.springs.j[e]) -
                   particle_position(s.particles, s.springs.i[e]);
    const Vec3 f = s.springs.stiffness[e] * (d.norm() - s.springs.rest_length[e]) * d.normalized();
    force[s.springs.i[e]] += f;
    force[s.springs.j[e]] -= f;
  }
  const Vec3 across = Vec3(-(b - a).y(), (b - a).x(), 0).normalized();
  int lips = 0, opening = 0;
  std::vector<uint32_t> fan;
  for (uint32_t v : path.sources) {
    // The two crack tips (c_0 and the tip) have material all round: no net pull expected.
    if (!s.particles.slots.alive(v) || v == path.tip || v == path.sources.front()) continue;
    if (!on_boundary(m, v)) continue;
    vertex_fan(s.triangles, s.topology.adjacency, s.topology.vertex_triangle[v], v, fan);
    Vec3 centroid = Vec3::Zero();
    for (uint32_t t : fan)
      for (int k = 0; k < 3; ++k)
        centroid += particle_position(s.particles, corner(s.triangles, t, k)) / (3.0 * fan.size());
    const double side = (centroid - particle_position(s.particles, v)).dot(across);
    ++lips;
    opening += force[v].dot(across) * side > 0;
    if (force[v].dot(across) * side <= 0)
      ADD_FAILURE() << "lip vertex " << v << " at " << particle_position(s.particles, v).transpose()
                    << " is pushed into the cut: force " << force[v].transpose();
  }
  EXPECT_GT(lips, 10);
  EXPECT_EQ(opening, lips) << "every lip vertex is pulled away from the cut";

  // Without pre-stretch the sheet is at rest: the cut does not open.
  CutSheet slack = cut_sheet(phaco::test::grid_mesh(10, 0.15), 0.0);
  CutMesh ms = slack.mesh();
  CutPath ps;
  for (int k = 0; k <= 20; ++k) cut_towards(ms, ps, a + (b - a) * (k / 20.0), settings(), log);
  double worst = 0;
  for (uint32_t e = 0; e < slack.springs.slots.size(); ++e) {
    if (!slack.springs.slots.alive(e)) continue;
    const Vec3 d = particle_position(slack.particles, slack.springs.j[e]) -
                   particle_position(slack.particles, slack.springs.i[e]);
    worst = std::max(worst, std::abs(d.norm() - slack.springs.rest_length[e]));
  }
  EXPECT_LT(worst, 1e-5) << "a cut through an unstressed sheet leaves every spring at rest";
}

// Distance from x to the polyline.
double to_polyline(const Vec3& x, const std::vector<Vec3>& line) {
  double best = 1e300;
  for (size_t k = 0; k + 1 < line.size(); ++k) {
    const Vec3 e = line[k + 1] - line[k];
    const double t =
        e.squaredNorm() > 0 ? std::clamp((x - line[k]).dot(e) / e.squaredNorm(), 0.0, 1.0) : 0.0;
    best = std::min(best, (x - (line[k] + t * e)).norm());
  }
  return best;
}

TEST(ProgressiveCut, TheCutEdgeStaysWithinTheSnapDistanceOfTheToolPath) {
  CutSheet s = cut_sheet(phaco::test::grid_mesh(14, 0.25));
  CutMesh m = s.mesh();
  CutPath path;
  EditLog log;
  // A curved stroke: a quarter circle of radius 5 sampled every 0.25 mm.
  std::vector<Vec3> tool;
  for (int k = 0; k <= 32; ++k) {
    const double th = 0.2 + 1.2 * k / 32.0;
    tool.push_back(P(1.5 + 5.0 * std::cos(th), 1.5 + 5.0 * std::sin(th)));
  }
  for (const Vec3& x : tool) cut_towards(m, path, x, settings(), log);
  ASSERT_TRUE(sound(s));
  // The cut edge: the lips, sampled at their ends and midpoints.
  double cut_to_tool = 0.0;
  std::vector<Vec3> cut_points;
  for (const auto& [u, w] : cut_lip_edges(s, 14)) {
    for (double f : {0.0, 0.5, 1.0}) {
      cut_points.push_back(u + f * (w - u));
      cut_to_tool = std::max(cut_to_tool, to_polyline(cut_points.back(), tool));
    }
  }
  ASSERT_GT(cut_points.size(), 20u);
  // And the tool path's distance to the cut edge (sampled finely).
  double tool_to_cut = 0.0;
  for (size_t k = 0; k + 1 < tool.size(); ++k)
    for (int f = 0; f < 10; ++f) {
      const Vec3 x = tool[k] + (tool[k + 1] - tool[k]) * (f / 10.0);
      double best = 1e300;
      for (const Vec3& c : cut_points) best = std::min(best, (c - x).norm());
      tool_to_cut = std::max(tool_to_cut, best);
    }
  const double hausdorff = std::max(cut_to_tool, tool_to_cut);
  RecordProperty("hausdorff_mm", std::to_string(hausdorff));
  RecordProperty("max_snap_mm", std::to_string(path.max_snap_mm));
  EXPECT_LE(cut_to_tool, path.max_snap_mm + 1e-4);
  // The far side samples the cut edge at its vertices and midpoints only: half an edge of slack.
  EXPECT_LE(tool_to_cut, path.max_snap_mm + 0.5);
  // Snapping never moves a point by more than a fraction of the local edge (unit grid): the
  // proximity thresholds, or the nearest feature when a split would make a sliver.
  EXPECT_LT(path.max_snap_mm, 0.35);
}

TEST(ProgressiveCut, RemeshingMergesAlongStraightCutsAndSavesElements) {
  uint32_t triangles[2] = {0, 0}, merges[2] = {0, 0};
  for (int remesh = 0; remesh < 2; ++remesh) {
    CutSheet s = cut_sheet(phaco::test::grid_mesh(12, 0.1));
    const uint32_t before = s.triangles.slots.live_count();
    CutMesh m = s.mesh();
    CutSettings cs = settings();
    cs.remesh = remesh == 1;
    CutPath path;
    EditLog log;
    for (int k = 0; k <= 40; ++k) cut_towards(m, path, P(1.5 + 0.2 * k, 5.3 + 0.01 * k), cs, log);
    ASSERT_TRUE(sound(s));
    triangles[remesh] = s.triangles.slots.live_count() - before;
    merges[remesh] = log.merges;
  }
  EXPECT_EQ(merges[0], 0u);
  EXPECT_GT(merges[1], 0u);
  EXPECT_LT(triangles[1], triangles[0]);
  RecordProperty("triangles_added_without_remesh", std::to_string(triangles[0]));
  RecordProperty("triangles_added_with_remesh", std::to_string(triangles[1]));
}

TEST(ProgressiveCut, BadInputIsRefusedWithoutChangingTheMesh) {
  CutSheet s = cut_sheet(phaco::test::grid_mesh(4, 0.0));
  CutMesh m = s.mesh();
  CutPath path;
  EditLog log;
  const double nan = std::nan("");
  EXPECT_THROW(cut_towards(m, path, P(nan, 1.0), settings(), log), std::invalid_argument);
  cut_towards(m, path, P(1.2, 1.3), settings(), log);
  EXPECT_THROW(cut_towards(m, path, Vec3(1.0, 1.0, INFINITY), settings(), log),
               std::invalid_argument);
  EXPECT_EQ(s.particles.slots.live_count(), 16u);
  EXPECT_THROW(split_edge(m, 0, 15, 0.5, log), std::invalid_argument) << "not an edge";
  EXPECT_THROW(split_edge(m, 0, 1, 1.0, log), std::invalid_argument) << "t outside (0, 1)";
  EXPECT_TRUE(sound(s));
}

}  // namespace
}  // namespace phaco::cut
