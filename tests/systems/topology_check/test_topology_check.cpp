#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <limits>
#include <numbers>
#include <set>
#include <string>
#include <vector>

#include "procedures/eye/eye_mesh.hpp"
#include "systems/springs/springs.hpp"
#include "systems/topology_check/topology_check.hpp"
#include "tests/support/fan_meshes.hpp"
#include "tests/support/membrane_tables.hpp"

namespace phaco {
namespace {

using topology_check::check_membrane;
using topology_check::ElementTable;
using topology_check::InvariantReport;
using topology_check::InvariantScratch;
using topology_check::Violation;

struct Membrane {
  Particles particles;
  Triangles triangles;
  Springs springs;
};

Membrane from_mesh(const SurfaceMesh& mesh) {
  Membrane m;
  m.particles = test::particles_from(mesh);
  m.triangles = test::triangles_from(mesh);
  m.springs = springs::build_springs(m.particles, m.triangles, {});
  return m;
}

// 5 × 5 vertices in the plane z = 0 (vertex j·5 + i at (i, j)), 4 × 4 unit cells, each split
// along its (i, j)–(i+1, j+1) diagonal into triangles 2·cell (lower) and 2·cell + 1 (upper), both
// counter-clockwise seen from +z. Cell (1, 1) is interior: triangles 10 and 11, diagonal (6, 12).
constexpr uint32_t kN = 5;
Membrane grid() {
  SurfaceMesh mesh;
  for (uint32_t j = 0; j < kN; ++j)
    for (uint32_t i = 0; i < kN; ++i) mesh.vertices.push_back({double(i), double(j), 0.0});
  for (uint32_t j = 0; j + 1 < kN; ++j) {
    for (uint32_t i = 0; i + 1 < kN; ++i) {
      const uint32_t v00 = j * kN + i, v10 = v00 + 1, v01 = v00 + kN, v11 = v01 + 1;
      mesh.triangles.push_back({v00, v10, v11});
      mesh.triangles.push_back({v00, v11, v01});
    }
  }
  return from_mesh(mesh);
}

uint32_t spring_of(const Springs& s, uint32_t a, uint32_t b) {
  for (uint32_t e = 0; e < s.slots.size(); ++e) {
    if (s.slots.alive(e) && s.i[e] == std::min(a, b) && s.j[e] == std::max(a, b)) return e;
  }
  ADD_FAILURE() << "no spring (" << a << ", " << b << ")";
  return 0;
}

uint32_t add_particle(Membrane& m, float x, float y, float z) {
  const uint32_t p = table_append(m.particles, 1);
  m.particles.x[p] = x;
  m.particles.y[p] = y;
  m.particles.z[p] = z;
  m.particles.inv_mass[p] = 1.0f;
  return p;
}

uint32_t add_triangle(Membrane& m, uint32_t a, uint32_t b, uint32_t c) {
  const uint32_t t = table_append(m.triangles, 1);
  m.triangles.a[t] = a;
  m.triangles.b[t] = b;
  m.triangles.c[t] = c;
  return t;
}

uint32_t add_spring(Membrane& m, uint32_t i, uint32_t j) {
  const uint32_t e = table_append(m.springs, 1);
  m.springs.i[e] = i;
  m.springs.j[e] = j;
  m.springs.rest_length[e] = 1.0f;
  m.springs.stiffness[e] = 1.0f;
  return e;
}

// A separate triangle at (10, 0, 0) + the given offsets, with its three springs: only its shape
// can be wrong.
uint32_t add_island(Membrane& m, float x1, float x2, float y2) {
  const uint32_t p0 = add_particle(m, 10.0f, 0.0f, 0.0f);
  const uint32_t p1 = add_particle(m, 10.0f + x1, 0.0f, 0.0f);
  const uint32_t p2 = add_particle(m, 10.0f + x2, y2, 0.0f);
  add_spring(m, p0, p1);
  add_spring(m, p1, p2);
  add_spring(m, p0, p2);
  return add_triangle(m, p0, p1, p2);
}

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();
constexpr uint32_t kNone = kInvalidIndex;

struct Case {
  const char* name;
  // Corrupts the grid; returns the expected (element, other) of the single record of `kind`.
  std::function<std::pair<uint32_t, uint32_t>(Membrane&)> corrupt;
  Violation kind;
  ElementTable table;
  std::set<Violation> also;  // kinds the corruption may also cause, besides `kind`
};

std::vector<Case> cases() {
  return {
      {"TriangleIndexOutOfRange",
       [](Membrane& m) {
         m.triangles.c[10] = 999;
         return std::pair{10u, 999u};
       },
       Violation::IndexOutOfRange,
       ElementTable::Triangle,
       {}},
      {"SpringIndexOutOfRange",
       [](Membrane& m) {
         const uint32_t e = spring_of(m.springs, 6, 12);
         m.springs.j[e] = 999;
         return std::pair{e, 999u};
       },
       Violation::IndexOutOfRange,
       ElementTable::Spring,
       {Violation::EdgeWithoutSpring}},
      {"TriangleOnDeadParticle",
       [](Membrane& m) {
         const uint32_t p = add_particle(m, 1.5f, 1.5f, 0.0f);
         table_remove(m.particles, p);
         m.triangles.c[10] = p;
         return std::pair{10u, p};
       },
       Violation::DeadParticleReferenced,
       ElementTable::Triangle,
       {}},
      {"SpringOnDeadParticle",
       [](Membrane& m) {
         const uint32_t p = add_particle(m, 1.5f, 1.5f, 0.0f);
         table_remove(m.particles, p);
         const uint32_t e = spring_of(m.springs, 6, 12);
         m.springs.j[e] = p;
         return std::pair{e, p};
       },
       Violation::DeadParticleReferenced,
       ElementTable::Spring,
       {Violation::EdgeWithoutSpring}},
      {"NaNPosition",
       [](Membrane& m) {
         m.particles.x[12] = kNaN;
         return std::pair{12u, kNone};
       },
       Violation::NonFinitePosition,
       ElementTable::Particle,
       {}},
      {"InfiniteVelocity",
       [](Membrane& m) {
         m.particles.vy[7] = std::numeric_limits<float>::infinity();
         return std::pair{7u, kNone};
       },
       Violation::NonFinitePosition,
       ElementTable::Particle,
       {}},
      {"RepeatedVertex",
       [](Membrane& m) {
         m.triangles.c[10] = m.triangles.a[10];
         return std::pair{10u, 6u};
       },
       Violation::DegenerateTriangle,
       ElementTable::Triangle,
       {}},
      {"ThirdTriangleOnEdge",
       [](Membrane& m) {
         const uint32_t p = add_particle(m, 1.5f, 1.5f, 1.0f);
         add_spring(m, 6, p);
         add_spring(m, 12, p);
         return std::pair{add_triangle(m, 6, 12, p), 10u};
       },
       Violation::EdgeWithMoreThanTwoTriangles,
       ElementTable::Triangle,
       {}},
      {"FlippedInteriorTriangle",
       [](Membrane& m) {
         std::swap(m.triangles.b[10], m.triangles.c[10]);
         return std::pair{10u, 3u};  // its first same-direction edge (6, 7) borders triangle 3
       },
       Violation::InconsistentOrientation,
       ElementTable::Triangle,
       {}},
      {"FlippedCornerTriangle",
       [](Membrane& m) {
         std::swap(m.triangles.b[0], m.triangles.c[0]);
         return std::pair{0u, 1u};  // edge (0, 6) borders triangle 1
       },
       Violation::InconsistentOrientation,
       ElementTable::Triangle,
       {}},
      {"ZeroAreaTriangle",
       [](Membrane& m) {
         return std::pair{add_island(m, 1.0f, 0.5f, 1e-9f), kNone};
       },
       Violation::SmallArea,
       ElementTable::Triangle,
       {}},
      {"Sliver",
       [](Membrane& m) {
         // Right angle at p1, 0.5° at p0.
         const float h = static_cast<float>(std::tan(0.5 * std::numbers::pi / 180.0));
         const uint32_t t = add_island(m, 1.0f, 1.0f, h);
         return std::pair{t, m.triangles.a[t]};
       },
       Violation::SmallAngle,
       ElementTable::Triangle,
       {}},
      {"SpringAcrossNoTriangle",
       [](Membrane& m) {
         return std::pair{add_spring(m, 0, 24), kNone};
       },
       Violation::SpringWithoutEdge,
       ElementTable::Spring,
       {}},
      {"MissingSpring",
       [](Membrane& m) {
         table_remove(m.springs, spring_of(m.springs, 6, 12));
         return std::pair{10u, kNone};
       },
       Violation::EdgeWithoutSpring,
       ElementTable::Triangle,
       {}},
      {"DuplicateSpring",
       [](Membrane& m) {
         const uint32_t first = spring_of(m.springs, 6, 12);
         return std::pair{add_spring(m, 12, 6) /* reversed too */, first};
       },
       Violation::DuplicateSpring,
       ElementTable::Spring,
       {Violation::SpringIndexOrder}},
      {"SpringIndexOrder",
       [](Membrane& m) {
         const uint32_t e = spring_of(m.springs, 6, 12);
         std::swap(m.springs.i[e], m.springs.j[e]);
         return std::pair{e, kNone};
       },
       Violation::SpringIndexOrder,
       ElementTable::Spring,
       {}},
      {"NaNStiffness",
       [](Membrane& m) {
         const uint32_t e = spring_of(m.springs, 6, 7);
         m.springs.stiffness[e] = kNaN;
         return std::pair{e, kNone};
       },
       Violation::NonFiniteSpring,
       ElementTable::Spring,
       {}},
      {"TriangleTouchingTheGridOnlyAtACorner",
       [](Membrane& m) {
         // Corner 24 at (4, 4) gets a second fan: a triangle beyond it, sharing no edge.
         const uint32_t p = add_particle(m, 5.0f, 4.0f, 0.0f);
         const uint32_t q = add_particle(m, 5.0f, 5.0f, 0.0f);
         add_spring(m, 24, p);
         add_spring(m, p, q);
         add_spring(m, 24, q);
         return std::pair{24u, add_triangle(m, 24, p, q)};
       },
       Violation::NonManifoldVertex,
       ElementTable::Particle,
       {}},
      {"NegativeRestLength",
       [](Membrane& m) {
         const uint32_t e = spring_of(m.springs, 0, 1);
         m.springs.rest_length[e] = -1.0f;
         return std::pair{e, kNone};
       },
       Violation::NonFiniteSpring,
       ElementTable::Spring,
       {}},
  };
}

TEST(CheckMembrane, GridIsValid) {
  const Membrane m = grid();
  const InvariantReport r = check_membrane(m.particles, m.triangles, m.springs);
  EXPECT_TRUE(r.ok()) << r.summary();
  EXPECT_EQ(r.checked_particles, 25u);
  EXPECT_EQ(r.checked_triangles, 32u);
  EXPECT_EQ(r.checked_springs, 56u);  // 2·4·5 sides + 16 diagonals
}

TEST(CheckMembrane, EachCorruptionIsReportedOnceWithItsElement) {
  std::set<Violation> covered;
  InvariantScratch scratch;  // shared across cases: scratch must carry nothing between calls
  for (const Case& c : cases()) {
    SCOPED_TRACE(c.name);
    Membrane m = grid();
    const auto [element, other] = c.corrupt(m);
    const InvariantReport r = check_membrane(m.particles, m.triangles, m.springs, {}, scratch);
    ASSERT_EQ(r.count(c.kind), 1u) << r.summary();
    for (const auto& v : r.violations) {
      if (v.kind == c.kind) {
        EXPECT_EQ(v.element, element) << v.detail;
        EXPECT_EQ(v.other, other) << v.detail;
        EXPECT_EQ(v.table, c.table) << v.detail;
        EXPECT_FALSE(v.detail.empty());
      } else {
        EXPECT_TRUE(c.also.count(v.kind))
            << "unexpected " << topology_check::to_string(v.kind) << ": " << v.detail;
      }
    }
    covered.insert(c.kind);
    // The same scratch on the clean grid again: nothing left over from the corrupt one.
    const Membrane clean = grid();
    EXPECT_TRUE(check_membrane(clean.particles, clean.triangles, clean.springs, {}, scratch).ok());
  }
  EXPECT_EQ(covered.size(), static_cast<size_t>(topology_check::kViolationKinds));
}

// Hand-made fans around vertex 0 (tests/support/fan_meshes.hpp): a disc and a half-disc pass; a
// bowtie, two or three boundary fans, two discs, a disc and a triangle are one record each, at
// vertex 0, naming a triangle of another fan, and nothing else is reported.
TEST(CheckMembrane, EachVertexIsOneDiscOrOneHalfDisc) {
  InvariantScratch scratch;
  for (const test::FanMesh& f : test::fan_meshes()) {
    SCOPED_TRACE(f.name);
    const Membrane m = from_mesh(f.mesh);
    const InvariantReport r = check_membrane(m.particles, m.triangles, m.springs, {}, scratch);
    if (f.fans_at_0 == 1) {
      EXPECT_TRUE(r.ok()) << r.summary();
      continue;
    }
    ASSERT_EQ(r.violations.size(), 1u) << r.summary();
    const auto& v = r.violations.front();
    EXPECT_EQ(v.kind, Violation::NonManifoldVertex);
    EXPECT_EQ(v.table, ElementTable::Particle);
    EXPECT_EQ(v.element, 0u);
    EXPECT_EQ(v.other, f.second_fan_triangle);
    EXPECT_NE(v.detail.find(std::to_string(f.fans_at_0) + " fans"), std::string::npos) << v.detail;
  }
}

// Cuts along the grid's row j = 2 made by hand: the triangles above the row (16..31) moved to
// copies of the row's vertices that the cut split. Each edge keeps at most two triangles, so the
// edge checks pass whatever is split; only the vertex check sees a cut through vertex 12 that
// forgot to duplicate it, where the two sides then touch: a bowtie.
TEST(CheckMembrane, ACutThroughAVertexItDidNotDuplicateLeavesABowtie) {
  auto cut = [](std::vector<uint32_t> split) {
    Membrane m = grid();
    std::vector<uint32_t> copy(kN * kN, kInvalidIndex);
    for (uint32_t v : split)
      copy[v] = add_particle(m, m.particles.x[v], m.particles.y[v], m.particles.z[v]);
    for (uint32_t t = 16; t < 32; ++t) {
      for (uint32_t* c : {&m.triangles.a[t], &m.triangles.b[t], &m.triangles.c[t]})
        if (copy[*c] != kInvalidIndex) *c = copy[*c];
    }
    m.springs = springs::build_springs(m.particles, m.triangles, {});
    return m;
  };
  const Membrane missed = cut({10, 11, 13, 14});  // across the sheet, 12 not duplicated
  const InvariantReport r = check_membrane(missed.particles, missed.triangles, missed.springs);
  ASSERT_EQ(r.violations.size(), 1u) << r.summary();
  EXPECT_EQ(r.violations.front().kind, Violation::NonManifoldVertex);
  EXPECT_EQ(r.violations.front().element, 12u);
  // A slit from the rim ending at 12: the tip is shared by both sides through edge (12, 13).
  const Membrane slit = cut({10, 11});
  const InvariantReport tip = check_membrane(slit.particles, slit.triangles, slit.springs);
  EXPECT_TRUE(tip.ok()) << tip.summary();
  // Across the sheet with 12 duplicated too: two halves, each a manifold.
  const Membrane through = cut({10, 11, 12, 13, 14});
  const InvariantReport halves =
      check_membrane(through.particles, through.triangles, through.springs);
  EXPECT_TRUE(halves.ok()) << halves.summary();
}

TEST(CheckMembrane, ShortColumnIsReportedWithoutReadingPastIt) {
  Membrane m = grid();
  m.particles.z.pop_back();  // particle 24 has no z
  const InvariantReport r = check_membrane(m.particles, m.triangles, m.springs);
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(r.violations.front().kind, Violation::IndexOutOfRange);
  EXPECT_EQ(r.violations.front().table, ElementTable::Particle);
  EXPECT_EQ(r.violations.front().element, 24u);
  EXPECT_EQ(r.checked_particles, 24u);
  // Triangles 30 and 31 and springs (18, 24), (19, 24) and (23, 24) name particle 24.
  EXPECT_EQ(r.count(Violation::IndexOutOfRange), 1u + 2u + 3u);
}

TEST(CheckMembrane, TombstonesAreIgnored) {
  Membrane m = grid();
  // Cell (1, 1) removed with its diagonal spring: a hole, still a valid membrane.
  table_remove(m.triangles, 10);
  table_remove(m.triangles, 11);
  table_remove(m.springs, spring_of(m.springs, 6, 12));
  // Dead elements with garbage in them.
  m.triangles.a[10] = 999;
  m.triangles.b[11] = m.triangles.c[11];
  const uint32_t p = add_particle(m, kNaN, kNaN, kNaN);
  table_remove(m.particles, p);
  const uint32_t e = add_spring(m, 999, p);
  m.springs.stiffness[e] = kNaN;
  table_remove(m.springs, e);
  const InvariantReport r = check_membrane(m.particles, m.triangles, m.springs);
  EXPECT_TRUE(r.ok()) << r.summary();
  EXPECT_EQ(r.checked_triangles, 30u);
  EXPECT_EQ(r.checked_springs, 55u);
  EXPECT_EQ(r.checked_particles, 25u);

  // The hole's edges are still edges of live triangles, so their springs must stay; the
  // diagonal's spring must go with its triangles.
  Membrane kept = grid();
  table_remove(kept.triangles, 10);
  table_remove(kept.triangles, 11);
  const InvariantReport r2 = check_membrane(kept.particles, kept.triangles, kept.springs);
  ASSERT_EQ(r2.violations.size(), 1u) << r2.summary();
  EXPECT_EQ(r2.violations[0].kind, Violation::SpringWithoutEdge);
  EXPECT_EQ(r2.violations[0].element, spring_of(kept.springs, 6, 12));
}

TEST(CheckMembrane, NaNPositionsAreReportedPerParticle) {
  Membrane m = grid();
  m.particles.z[3] = kNaN;
  m.particles.y[20] = -std::numeric_limits<float>::infinity();
  const InvariantReport r = check_membrane(m.particles, m.triangles, m.springs);
  ASSERT_EQ(r.violations.size(), 2u) << r.summary();
  EXPECT_EQ(r.count(Violation::NonFinitePosition), 2u);
  EXPECT_EQ(r.violations[0].element, 3u);
  EXPECT_EQ(r.violations[1].element, 20u);
}

TEST(CheckMembrane, AngleThresholdIsRespected) {
  // A 2° corner passes the default 1° and fails at 3°.
  Membrane m = grid();
  const float h = static_cast<float>(std::tan(2.0 * std::numbers::pi / 180.0));
  add_island(m, 1.0f, 1.0f, h);
  EXPECT_TRUE(check_membrane(m.particles, m.triangles, m.springs).ok());
  const InvariantReport r =
      check_membrane(m.particles, m.triangles, m.springs, {.min_angle_deg = 3.0});
  EXPECT_EQ(r.count(Violation::SmallAngle), 1u) << r.summary();
  EXPECT_EQ(r.violations.size(), 1u);
  // An area threshold above the grid's 0.5 mm² flags all 32 grid triangles and the island.
  const InvariantReport big =
      check_membrane(m.particles, m.triangles, m.springs, {.min_area_mm2 = 0.6});
  EXPECT_EQ(big.count(Violation::SmallArea), 33u);  // the island's area is h/2 ≈ 0.017 mm²
}

TEST(CheckMembrane, SummaryNamesKindsAndCounts) {
  Membrane m = grid();
  std::swap(m.triangles.b[10], m.triangles.c[10]);
  m.particles.x[0] = kNaN;
  m.particles.x[24] = kNaN;
  const InvariantReport r = check_membrane(m.particles, m.triangles, m.springs);
  const std::string s = r.summary();
  EXPECT_NE(s.find("3 violations"), std::string::npos) << s;
  EXPECT_NE(s.find("2 NonFinitePosition"), std::string::npos) << s;
  EXPECT_NE(s.find("1 InconsistentOrientation"), std::string::npos) << s;
  const std::string short_summary = r.summary(1);
  EXPECT_NE(short_summary.find("... and 2 more"), std::string::npos) << short_summary;
  const Membrane clean = grid();
  EXPECT_NE(check_membrane(clean.particles, clean.triangles, clean.springs)
                .summary()
                .find("0 violations"),
            std::string::npos);
}

TEST(CheckMembrane, KindNamesAreDistinct) {
  std::set<std::string_view> names;
  for (int k = 0; k < topology_check::kViolationKinds; ++k) {
    names.insert(topology_check::to_string(static_cast<Violation>(k)));
  }
  EXPECT_EQ(names.size(), static_cast<size_t>(topology_check::kViolationKinds));
  EXPECT_EQ(names.count("Unknown"), 0u);
}

class CapsuleMesh : public ::testing::TestWithParam<std::tuple<int, eye::CapsuleLayout>> {};

TEST_P(CapsuleMesh, PassesWithZeroViolations) {
  const auto [level, layout] = GetParam();
  const Membrane m = from_mesh(
      eye::make_capsule(eye::default_eye_params(), eye::resolution_for_level(level), layout));
  InvariantScratch scratch;
  const InvariantReport r = check_membrane(m.particles, m.triangles, m.springs, {}, scratch);
  EXPECT_TRUE(r.ok()) << r.summary();
  EXPECT_EQ(r.checked_particles, m.particles.slots.live_count());
  EXPECT_EQ(r.checked_triangles, m.triangles.slots.live_count());
  EXPECT_EQ(r.checked_springs, m.springs.slots.live_count());
  EXPECT_GT(r.checked_triangles, 500u);
  // The warm scratch gives the same answer.
  EXPECT_TRUE(check_membrane(m.particles, m.triangles, m.springs, {}, scratch).ok());
}

INSTANTIATE_TEST_SUITE_P(Levels, CapsuleMesh,
                         ::testing::Combine(::testing::Values(0, 3),
                                            ::testing::Values(eye::CapsuleLayout::Curvilinear,
                                                              eye::CapsuleLayout::Isotropic)),
                         [](const auto& info) {
                           std::string name = eye::to_string(std::get<1>(info.param));
                           name += "_level";
                           name += std::to_string(std::get<0>(info.param));
                           return name;
                         });

}  // namespace
}  // namespace phaco
