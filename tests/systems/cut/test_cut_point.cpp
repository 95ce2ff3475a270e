#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <vector>

#include "procedures/eye/eye_mesh.hpp"
#include "systems/cut/cut_point.hpp"
#include "systems/cut/segment_trace.hpp"
#include "tests/support/grid_mesh.hpp"
#include "tests/support/membrane_tables.hpp"

namespace phaco::cut {
namespace {

struct Sheet {
  Particles particles;
  Triangles triangles;
  TriangleAdjacency adjacency;
};

Sheet from_mesh(const SurfaceMesh& mesh) {
  Sheet s;
  s.particles = test::particles_from(mesh);
  s.triangles = test::triangles_from(mesh);
  s.adjacency = build_triangle_adjacency(s.triangles, static_cast<uint32_t>(mesh.vertices.size()));
  return s;
}

// The unit grid of tests/support/grid_mesh.hpp.
Sheet grid(int n, double jitter) {
  return from_mesh(test::grid_mesh(n, jitter));
}

Vec3 pos(const Sheet& s, uint32_t v) {
  return particle_position(s.particles, v);
}

// Deterministic points in [lo, hi]^2.
Vec3 sample(int k, double lo, double hi) {
  const double u = std::fmod(0.6180339887 * (k + 1), 1.0),
               w = std::fmod(0.7548776662 * (k + 1), 1.0);
  return Vec3(lo + (hi - lo) * u, lo + (hi - lo) * w, 0.0);
}

CutPoint locate(const Sheet& s, const Vec3& x, const SnapSettings& snap = {}, uint32_t start = 0) {
  return locate_cut_point(s.particles, s.triangles, s.adjacency, start, x, snap);
}

bool same(const CutPoint& l, const CutPoint& r) {
  return l.kind == r.kind && l.triangle == r.triangle && l.a == r.a && l.b == r.b && l.t == r.t &&
         l.bary == r.bary && l.position == r.position && l.distance_mm == r.distance_mm;
}

TEST(Adjacency, GridNeighboursAreMutualAndRimCountIsRight) {
  const Sheet s = grid(6, 0.2);
  int rim = 0;
  for (uint32_t t = 0; t < s.triangles.slots.size(); ++t)
    for (int k = 0; k < 3; ++k) {
      const uint32_t n = s.adjacency.neighbour[t][k];
      if (n == kInvalidIndex) {
        ++rim;
        continue;
      }
      const auto& back = s.adjacency.neighbour[n];
      EXPECT_NE(std::find(back.begin(), back.end(), t), back.end());
    }
  EXPECT_EQ(rim, 4 * 5);
}

TEST(Adjacency, BadIndicesThrow) {
  Sheet s = grid(3, 0.0);
  EXPECT_THROW(build_triangle_adjacency(s.triangles, 5), std::invalid_argument);
  s.triangles.c[0] = s.triangles.a[0];
  EXPECT_THROW(build_triangle_adjacency(s.triangles, 9), std::invalid_argument);
}

TEST(Locate, ExactVerticesEdgesAndFaces) {
  const Sheet s = grid(7, 0.2);
  const SnapSettings snap{0.0, 0.0};  // exact hits must classify without any snapping
  for (uint32_t v = 0; v < s.particles.slots.size(); ++v) {
    const CutPoint c = locate(s, pos(s, v), snap);
    ASSERT_EQ(c.kind, CutPoint::Vertex) << v;
    EXPECT_EQ(c.a, v);
    EXPECT_EQ(c.distance_mm, 0.0);
  }
  for (uint32_t t = 0; t < s.triangles.slots.size(); ++t) {
    const uint32_t v[3] = {s.triangles.a[t], s.triangles.b[t], s.triangles.c[t]};
    const Vec3 centroid = (pos(s, v[0]) + pos(s, v[1]) + pos(s, v[2])) / 3.0;
    const CutPoint f = locate(s, centroid + Vec3(0, 0, 0.25), snap);
    ASSERT_EQ(f.kind, CutPoint::Face);
    EXPECT_EQ(f.triangle, t);
    EXPECT_NEAR(f.bary.x(), 1.0 / 3.0, 1e-9);
    EXPECT_NEAR(f.distance_mm, 0.25, 1e-9);
    for (int k = 0; k < 3; ++k) {
      const uint32_t a = std::min(v[k], v[(k + 1) % 3]), b = std::max(v[k], v[(k + 1) % 3]);
      const CutPoint e = locate(s, 0.75 * pos(s, a) + 0.25 * pos(s, b), snap);
      ASSERT_EQ(e.kind, CutPoint::Edge);
      EXPECT_EQ(e.a, a);
      EXPECT_EQ(e.b, b);
      EXPECT_NEAR(e.t, 0.25, 1e-9);
      const uint32_t n = s.adjacency.neighbour[t][k];
      EXPECT_EQ(e.triangle, n == kInvalidIndex ? t : std::min(t, n));
    }
  }
}

TEST(Locate, SnapThresholdBoundaries) {
  const Sheet s = grid(7, 0.2);
  const uint32_t t = 30;  // an interior triangle
  const uint32_t v0 = s.triangles.a[t], v1 = s.triangles.b[t], v2 = s.triangles.c[t];
  const Vec3 centroid = (pos(s, v0) + pos(s, v1) + pos(s, v2)) / 3.0;
  const double r = 0.05;

  // Towards the centroid from v0: inside the vertex radius snaps, just beyond does not.
  const Vec3 dir = (centroid - pos(s, v0)).normalized();
  const SnapSettings vsnap{r, 0.0};
  EXPECT_EQ(locate(s, pos(s, v0) + dir * (r * (1 - 1e-6)), vsnap).kind, CutPoint::Vertex);
  const CutPoint beyond = locate(s, pos(s, v0) + dir * (r * (1 + 1e-4)), vsnap);
  EXPECT_EQ(beyond.kind, CutPoint::Face);
  EXPECT_EQ(beyond.triangle, t);

  // Along the edge v0-v1 just past the vertex radius: the edge, not the vertex.
  const Vec3 along = (pos(s, v1) - pos(s, v0)).normalized();
  const CutPoint on_edge = locate(s, pos(s, v0) + along * (r * 1.01), vsnap);
  EXPECT_EQ(on_edge.kind, CutPoint::Edge);

  // Perpendicular off the mid-edge into t: inside the edge band snaps, just beyond is the face.
  const Vec3 mid = 0.5 * (pos(s, v0) + pos(s, v1));
  Vec3 in = Vec3(0, 0, 1).cross(along);  // counter-clockwise triangle: interior is on the left
  const SnapSettings esnap{0.0, r};
  const CutPoint e = locate(s, mid + in * (r * (1 - 1e-6)), esnap);
  ASSERT_EQ(e.kind, CutPoint::Edge);
  EXPECT_EQ(e.a, std::min(v0, v1));
  EXPECT_NEAR((e.position - mid).norm(), 0.0, 1e-6);
  const CutPoint f = locate(s, mid + in * (r * (1 + 1e-4)), esnap);
  EXPECT_EQ(f.kind, CutPoint::Face);
  EXPECT_EQ(f.triangle, t);
  // The vertex snap is tested before the edge snap.
  const SnapSettings both{0.1, 0.1};
  EXPECT_EQ(locate(s, pos(s, v0) + along * 0.05 + in * 0.05, both).kind, CutPoint::Vertex);
}

TEST(Locate, WalkGivesTheSameAnswerFromEveryStartAndMatchesTheScan) {
  const Sheet s = grid(10, 0.25);
  const SnapSettings snap{0.02, 0.01};
  for (int k = 0; k < 40; ++k) {
    const Vec3 x = sample(k, -0.5, 9.5) + Vec3(0, 0, 0.1 * (k % 3));  // some outside the rim
    const CutPoint ref = locate(s, x, snap, kInvalidIndex);           // scan
    for (uint32_t start = 0; start < s.triangles.slots.size(); ++start)
      ASSERT_TRUE(same(locate(s, x, snap, start), ref)) << "point " << k << " start " << start;
  }
}

TEST(Locate, PointsOutsideTheRimLandOnTheRim) {
  const Sheet s = grid(5, 0.2);
  const CutPoint e = locate(s, Vec3(1.5, -0.7, 0.0));
  ASSERT_EQ(e.kind, CutPoint::Edge);
  EXPECT_EQ(e.a, 1u);
  EXPECT_EQ(e.b, 2u);
  EXPECT_NEAR(e.t, 0.5, 1e-9);
  EXPECT_NEAR(e.distance_mm, 0.7, 1e-7);
  const CutPoint v = locate(s, Vec3(-1.0, -1.0, 0.5));
  ASSERT_EQ(v.kind, CutPoint::Vertex);
  EXPECT_EQ(v.a, 0u);
}

TEST(Locate, NonFiniteInputThrows) {
  const Sheet s = grid(4, 0.1);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(locate(s, Vec3(nan, 0, 0)), std::invalid_argument);
  EXPECT_THROW(locate(s, Vec3(0, std::numeric_limits<double>::infinity(), 0)),
               std::invalid_argument);
  EXPECT_THROW(locate(s, Vec3(1, 1, 0), SnapSettings{nan, 0.01}), std::invalid_argument);
  EXPECT_THROW(locate(s, Vec3(1, 1, 0), SnapSettings{0.01, -1.0}), std::invalid_argument);
  TriangleAdjacency wrong;
  EXPECT_THROW(locate_cut_point(s.particles, s.triangles, wrong, 0, Vec3(1, 1, 0), {}),
               std::invalid_argument);
  CutPoint bad = locate(s, Vec3(1.2, 1.3, 0));
  const CutPoint good = bad;
  bad.position.x() = nan;
  EXPECT_THROW(trace_segment(s.particles, s.triangles, s.adjacency, bad, good, {}),
               std::invalid_argument);
  bad = good;
  bad.triangle = 10'000;
  EXPECT_THROW(trace_segment(s.particles, s.triangles, s.adjacency, good, bad, {}),
               std::invalid_argument);
}

// Every proper crossing of the 2D segment with a mesh edge, ordered along the segment.
struct Hit {
  uint32_t a, b;
  double t, s;
};
std::vector<Hit> brute_force(const Sheet& s, const Vec3& p, const Vec3& q, double* closest_vertex) {
  std::vector<Hit> hits;
  *closest_vertex = std::numeric_limits<double>::infinity();
  std::vector<std::pair<uint32_t, uint32_t>> edges;
  for (uint32_t t = 0; t < s.triangles.slots.size(); ++t)
    for (int k = 0; k < 3; ++k) {
      const uint32_t u = corner(s.triangles, t, k), v = corner(s.triangles, t, (k + 1) % 3);
      edges.emplace_back(std::min(u, v), std::max(u, v));
    }
  std::sort(edges.begin(), edges.end());
  edges.erase(std::unique(edges.begin(), edges.end()), edges.end());
  const Vec3 d = q - p;
  for (auto [a, b] : edges) {
    const Vec3 A = pos(s, a), e = pos(s, b) - A;
    const double den = d.x() * e.y() - d.y() * e.x();
    if (std::abs(den) < 1e-15) continue;
    const Vec3 w = A - p;
    const double sp = (w.x() * e.y() - w.y() * e.x()) / den;
    const double te = (w.x() * d.y() - w.y() * d.x()) / den;
    if (sp <= 0 || sp >= 1 || te < 0 || te > 1) continue;
    *closest_vertex = std::min({*closest_vertex, te * e.norm(), (1 - te) * e.norm()});
    hits.push_back({a, b, te, sp});
  }
  std::sort(hits.begin(), hits.end(), [](const Hit& l, const Hit& r) { return l.s < r.s; });
  return hits;
}

TEST(Trace, MatchesBruteForceOnAFlatGridAcrossOneTwoAndManyTriangles) {
  const Sheet s = grid(10, 0.25);
  const SnapSettings snap{1e-4, 1e-4};
  int one = 0, two = 0, many = 0;
  SegmentTrace tr;
  for (int k = 0; k < 600; ++k) {
    const Vec3 p = sample(2 * k, 0.05, 8.95);
    // Short, medium and long segments.
    const double len = (k % 3 == 0) ? 0.3 : (k % 3 == 1 ? 1.0 : 6.0);
    const double ang = 2.399963 * k;
    Vec3 q = p + len * Vec3(std::cos(ang), std::sin(ang), 0);
    q = q.cwiseMax(Vec3(0.05, 0.05, 0)).cwiseMin(Vec3(8.95, 8.95, 0));
    double near_vertex = 0;
    const std::vector<Hit> ref = brute_force(s, p, q, &near_vertex);
    if (near_vertex < 1e-3) continue;  // vertex passes are tested on their own
    const CutPoint from = locate(s, p, snap), to = locate(s, q, snap);
    if (from.kind != CutPoint::Face || to.kind != CutPoint::Face) continue;
    trace_segment(s.particles, s.triangles, s.adjacency, from, to, snap, tr);
    ASSERT_TRUE(tr.complete) << k;
    ASSERT_EQ(tr.crossings.size(), ref.size()) << k;
    ASSERT_EQ(tr.triangles.size(), ref.size() + 1);
    EXPECT_EQ(tr.triangles.front(), from.triangle);
    EXPECT_EQ(tr.triangles.back(), to.triangle);
    for (size_t i = 0; i < ref.size(); ++i) {
      EXPECT_EQ(tr.crossings[i].kind, Crossing::Edge);
      EXPECT_EQ(tr.crossings[i].a, ref[i].a);
      EXPECT_EQ(tr.crossings[i].b, ref[i].b);
      EXPECT_NEAR(tr.crossings[i].t, ref[i].t, 1e-9);
      EXPECT_NEAR(tr.crossings[i].s, ref[i].s, 1e-9);
    }
    (ref.empty() ? one : ref.size() == 1 ? two : many) += 1;
  }
  EXPECT_GT(one, 20);
  EXPECT_GT(two, 20);
  EXPECT_GT(many, 100);
}

TEST(Trace, ThroughAVertexIsOneVertexCrossing) {
  const Sheet s = grid(8, 0.2);
  const SnapSettings snap{1e-6, 1e-6};
  int checked = 0;
  for (uint32_t v : {19u, 27u, 36u, 44u}) {
    for (int k = 0; k < 8; ++k) {
      const double ang = 0.3 + 0.785 * k;
      const Vec3 d(std::cos(ang), std::sin(ang), 0);
      const Vec3 p = pos(s, v) - 0.8 * d, q = pos(s, v) + 1.7 * d;
      const CutPoint from = locate(s, p, snap), to = locate(s, q, snap);
      const SegmentTrace tr = trace_segment(s.particles, s.triangles, s.adjacency, from, to, snap);
      ASSERT_TRUE(tr.complete);
      int at_v = 0;
      for (const Crossing& c : tr.crossings) {
        if (c.kind == Crossing::Vertex) {
          EXPECT_EQ(c.a, v);
          ++at_v;
        } else {
          EXPECT_NE(c.a, v);  // no edge crossing right at the vertex
          EXPECT_NE(c.b, v);
        }
      }
      EXPECT_EQ(at_v, 1);
      for (size_t i = 1; i < tr.crossings.size(); ++i)
        EXPECT_GE(tr.crossings[i].s, tr.crossings[i - 1].s);
      ++checked;
    }
  }
  EXPECT_EQ(checked, 32);
}

TEST(Trace, PassingWithinTheVertexSnapIsAVertexCrossing) {
  const Sheet s = grid(8, 0.2);
  const uint32_t v = 27;
  const double r = 0.01;
  const SnapSettings snap{r, 1e-6};
  for (int k = 0; k < 8; ++k) {
    const double ang = 0.3 + 0.785 * k;
    const Vec3 d(std::cos(ang), std::sin(ang), 0), side(-d.y(), d.x(), 0);
    for (double off : {0.5 * r, 2.0 * r}) {
      const Vec3 p = pos(s, v) + side * off - 0.8 * d, q = pos(s, v) + side * off + 1.7 * d;
      const SegmentTrace tr = trace_segment(s.particles, s.triangles, s.adjacency,
                                            locate(s, p, snap), locate(s, q, snap), snap);
      ASSERT_TRUE(tr.complete);
      int at_v = 0, touching_v = 0;
      for (const Crossing& c : tr.crossings) {
        at_v += c.kind == Crossing::Vertex && c.a == v;
        touching_v += c.kind == Crossing::Edge && (c.a == v || c.b == v);
        if (c.kind == Crossing::Edge) {  // an edge crossing is never within the snap of its ends
          EXPECT_GT((c.position - pos(s, c.a)).norm(), r);
          EXPECT_GT((c.position - pos(s, c.b)).norm(), r);
        }
      }
      EXPECT_EQ(at_v, off < r ? 1 : 0) << k << " " << off;
      if (off > r) {
        EXPECT_GE(touching_v, 1);  // missing the vertex means crossing one of its edges
      }
    }
  }
}

TEST(Locate, CapsuleWalkFromEveryStart) {
  const Sheet s = from_mesh(eye::make_capsule(
      eye::default_eye_params(), eye::resolution_for_level(0), eye::CapsuleLayout::Curvilinear));
  const SnapSettings snap{0.01, 0.005};
  const double z0 = pos(s, 0).z();  // vertex 0 is the centre of the cap
  for (int k = 0; k < 7; ++k) {
    // Above and below the cap, and (last) beyond its rim.
    const Vec3 x =
        k == 6 ? Vec3(9.0, 1.0, z0) : sample(k, -3.5, 3.5) + Vec3(0, 0, z0 + (k % 2 ? 0.3 : -0.2));
    const CutPoint ref = locate(s, x, snap, kInvalidIndex);
    for (uint32_t start = 0; start < s.triangles.slots.size(); ++start)
      ASSERT_TRUE(same(locate(s, x, snap, start), ref)) << k << " " << start;
  }
}

TEST(Trace, AlongEdgesIsTheChainOfVertices) {
  const Sheet s = grid(7, 0.0);  // straight grid lines
  const SnapSettings snap{1e-6, 1e-6};
  // Vertex (1,2) to vertex (5,2) along the grid line y = 2.
  const CutPoint from = locate(s, pos(s, 2 * 7 + 1), snap), to = locate(s, pos(s, 2 * 7 + 5), snap);
  const SegmentTrace tr = trace_segment(s.particles, s.triangles, s.adjacency, from, to, snap);
  ASSERT_TRUE(tr.complete);
  ASSERT_EQ(tr.crossings.size(), 3u);
  for (int i = 0; i < 3; ++i) {
    EXPECT_EQ(tr.crossings[i].kind, Crossing::Vertex);
    EXPECT_EQ(tr.crossings[i].a, static_cast<uint32_t>(2 * 7 + 2 + i));
    EXPECT_NEAR(tr.crossings[i].s, (i + 1) / 4.0, 1e-12);
  }
  // Inside one edge: no crossing, one triangle.
  const Vec3 a = pos(s, 8), b = pos(s, 9);
  const CutPoint e0 = locate(s, 0.8 * a + 0.2 * b, snap), e1 = locate(s, 0.3 * a + 0.7 * b, snap);
  ASSERT_EQ(e0.kind, CutPoint::Edge);
  const SegmentTrace in_edge = trace_segment(s.particles, s.triangles, s.adjacency, e0, e1, snap);
  EXPECT_TRUE(in_edge.complete);
  EXPECT_TRUE(in_edge.crossings.empty());
  EXPECT_EQ(in_edge.triangles.size(), 1u);
  // Diagonal through vertices on a straight grid: every quad diagonal (i + j even) or vertex.
  const CutPoint d0 = locate(s, Vec3(0.5, 0.5, 0), snap), d1 = locate(s, Vec3(4.5, 4.5, 0), snap);
  const SegmentTrace diag = trace_segment(s.particles, s.triangles, s.adjacency, d0, d1, snap);
  ASSERT_TRUE(diag.complete);
  ASSERT_EQ(diag.crossings.size(), 4u);
  for (int i = 0; i < 4; ++i) {
    EXPECT_EQ(diag.crossings[i].kind, Crossing::Vertex);
    EXPECT_EQ(diag.crossings[i].a, static_cast<uint32_t>((i + 1) * 8));
  }
}

TEST(Trace, EdgeAndVertexEndpointsAndTheRim) {
  const Sheet s = grid(6, 0.2);
  const SnapSettings snap{1e-4, 1e-4};
  // From the rim (a point outside lands on a rim edge) to an interior vertex.
  const CutPoint rim = locate(s, Vec3(2.5, -1.0, 0), snap);
  ASSERT_EQ(rim.kind, CutPoint::Edge);
  EXPECT_EQ(s.adjacency.neighbour[rim.triangle][0] == kInvalidIndex ||
                s.adjacency.neighbour[rim.triangle][1] == kInvalidIndex ||
                s.adjacency.neighbour[rim.triangle][2] == kInvalidIndex,
            true);
  const CutPoint v = locate(s, pos(s, 3 * 6 + 2), snap);
  ASSERT_EQ(v.kind, CutPoint::Vertex);
  for (const auto& [p, q] : {std::pair{rim, v}, std::pair{v, rim}}) {
    const SegmentTrace tr = trace_segment(s.particles, s.triangles, s.adjacency, p, q, snap);
    ASSERT_TRUE(tr.complete);
    double near_vertex = 0;
    const auto ref = brute_force(s, p.position, q.position, &near_vertex);
    size_t edges = 0;
    for (const Crossing& c : tr.crossings) edges += c.kind == Crossing::Edge;
    size_t ref_edges = 0;  // brute force also meets the edges at the end vertex
    for (const Hit& h : ref) ref_edges += (h.a != v.a && h.b != v.a);
    EXPECT_EQ(edges, ref_edges);
  }
}

TEST(Trace, CapsuleLevel0WalksAndTracesConsistently) {
  const Sheet s = from_mesh(eye::make_capsule(
      eye::default_eye_params(), eye::resolution_for_level(0), eye::CapsuleLayout::Curvilinear));
  const SnapSettings snap{0.01, 0.005};
  const uint32_t nt = s.triangles.slots.size();
  for (uint32_t v = 0; v < s.particles.slots.size(); ++v) {
    const CutPoint c = locate(s, pos(s, v), snap, (v * 7919u) % nt);
    ASSERT_EQ(c.kind, CutPoint::Vertex);
    EXPECT_EQ(c.a, v);
  }
  std::vector<CutPoint> pts;
  for (uint32_t t = 0; t < nt; t += 3) {
    const Vec3 centroid =
        (pos(s, s.triangles.a[t]) + pos(s, s.triangles.b[t]) + pos(s, s.triangles.c[t])) / 3.0;
    const CutPoint c = locate(s, centroid, snap, (t * 104729u) % nt);
    ASSERT_EQ(c.kind, CutPoint::Face);
    EXPECT_EQ(c.triangle, t);
    EXPECT_LT(c.distance_mm, 1e-9);
    EXPECT_TRUE(same(c, locate(s, centroid, snap, kInvalidIndex)));
    pts.push_back(c);
  }
  // Traces between many pairs: complete, and consecutive triangles share the crossing's feature.
  for (size_t i = 0; i + 1 < pts.size(); ++i) {
    const CutPoint& p = pts[i];
    const CutPoint& q = pts[(i * 13 + 5) % pts.size()];
    const SegmentTrace tr = trace_segment(s.particles, s.triangles, s.adjacency, p, q, snap);
    ASSERT_TRUE(tr.complete) << i;
    EXPECT_EQ(tr.triangles.front(), p.triangle);
    EXPECT_EQ(tr.triangles.back(), q.triangle);
    ASSERT_EQ(tr.triangles.size(), tr.crossings.size() + 1);
    for (size_t k = 0; k < tr.crossings.size(); ++k) {
      const Crossing& c = tr.crossings[k];
      for (uint32_t t : {tr.triangles[k], tr.triangles[k + 1]}) {
        const uint32_t v[3] = {s.triangles.a[t], s.triangles.b[t], s.triangles.c[t]};
        EXPECT_NE(std::find(v, v + 3, c.a), v + 3);
        if (c.kind == Crossing::Edge) {
          EXPECT_NE(std::find(v, v + 3, c.b), v + 3);
        }
      }
    }
    // Deterministic: the same call gives the same bits.
    const SegmentTrace again = trace_segment(s.particles, s.triangles, s.adjacency, p, q, snap);
    ASSERT_EQ(again.crossings.size(), tr.crossings.size());
    for (size_t k = 0; k < tr.crossings.size(); ++k) {
      EXPECT_EQ(again.crossings[k].position, tr.crossings[k].position);
      EXPECT_EQ(again.crossings[k].t, tr.crossings[k].t);
    }
  }
}

}  // namespace
}  // namespace phaco::cut
