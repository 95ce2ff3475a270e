#include <gtest/gtest.h>
#include <oneapi/tbb/global_control.h>
#include <oneapi/tbb/task_arena.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "procedures/eye/eye_mesh.hpp"
#include "systems/springs/springs.hpp"
#include "tests/support/membrane_tables.hpp"

namespace phaco {
namespace {

using springs::SpringMaterial;

struct Sheet {
  Particles particles;
  Triangles triangles;
};

Sheet from_mesh(const SurfaceMesh& mesh) {
  Sheet s;
  s.particles = test::particles_from(mesh);
  s.triangles = test::triangles_from(mesh);
  return s;
}

Sheet capsule(int level) {
  return from_mesh(eye::make_capsule(eye::default_eye_params(), eye::resolution_for_level(level),
                                     eye::CapsuleLayout::Curvilinear));
}

// Two triangles sharing the diagonal of the unit square: (0,0) (1,0) (1,1) and (0,0) (1,1) (0,1).
Sheet square() {
  SurfaceMesh m;
  m.vertices = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}};
  m.triangles = {{0, 1, 2}, {0, 2, 3}};
  return from_mesh(m);
}

TEST(BuildSprings, OneSpringPerEdgeWithAreaWeights) {
  Sheet s = square();
  const Springs sp = springs::build_springs(s.particles, s.triangles, {.sheet_modulus_mn_mm = 2.0});
  ASSERT_EQ(sp.slots.size(), 5u);
  for (uint32_t e = 0; e < 5; ++e) {
    EXPECT_LT(sp.i[e], sp.j[e]);
    if (e > 0) {
      EXPECT_TRUE(sp.i[e - 1] < sp.i[e] || (sp.i[e - 1] == sp.i[e] && sp.j[e - 1] < sp.j[e]));
    }
  }
  // The diagonal (0,2) has both triangles: k = 2·(0.5 + 0.5)/2 = 1; a side has one: k = 2·0.5/1
  // = 1.
  for (uint32_t e = 0; e < 5; ++e) {
    EXPECT_NEAR(sp.stiffness[e], 1.0, 1e-6) << e;
    EXPECT_NEAR(sp.rest_length[e], (sp.i[e] == 0 && sp.j[e] == 2) ? std::sqrt(2.0) : 1.0, 1e-6);
  }
  const Springs uniform = springs::build_springs(
      s.particles, s.triangles,
      {.weighting = StiffnessWeighting::Uniform, .sheet_modulus_mn_mm = 2.0});
  for (uint32_t e = 0; e < 5; ++e) EXPECT_NEAR(uniform.stiffness[e], std::sqrt(3.0), 1e-6);
}

TEST(BuildSprings, AreaWeightEqualsUniformOnEquilateralTriangles) {
  SurfaceMesh m;
  const double h = std::sqrt(3.0) / 2.0;
  m.vertices = {{0, 0, 0}, {1, 0, 0}, {0.5, h, 0}, {1.5, h, 0}};
  m.triangles = {{0, 1, 2}, {1, 3, 2}};
  Sheet s = from_mesh(m);
  const Springs sp = springs::build_springs(s.particles, s.triangles, {.sheet_modulus_mn_mm = 1.0});
  for (uint32_t e = 0; e < sp.slots.size(); ++e) {
    const bool shared = sp.i[e] == 1 && sp.j[e] == 2;
    EXPECT_NEAR(sp.stiffness[e], shared ? std::sqrt(3.0) / 2.0 : std::sqrt(3.0) / 4.0, 1e-6) << e;
  }
}

// Issue 18: a cotangent pre-tension that would need a rest length below half an edge (here the
// unit square's sides at pre-stretch 0.4: extension 1.5 × 0.4 = 0.6 of the edge) gives that edge
// the uniform pre-stretch and counts it, as the cut's re-springing does; before, the build threw,
// and a bowed capsule (difficulty anterior_bowing_kpa 1.9, in range) ended `phaco run` in exit 1.
TEST(BuildSprings, CotangentPretensionTooHighForAnEdgeFallsBackToUniformAndIsCounted) {
  Sheet s = square();
  const springs::SpringMaterial low{.prestretch = 0.2,
                                    .pretension = springs::Pretension::Cotangent};
  uint32_t clamped = 0;
  const Springs fine = springs::build_springs(s.particles, s.triangles, low, &clamped);
  EXPECT_EQ(clamped, 0u);
  EXPECT_NEAR(fine.rest_length[0], 1.0 - 1.5 * 0.2, 1e-6)
      << "side (0, 1): the cotangent rest length";

  springs::SpringMaterial high = low;
  high.prestretch = 0.4;
  const Springs sp = springs::build_springs(s.particles, s.triangles, high, &clamped);
  EXPECT_EQ(clamped, 4u) << "the four sides; the diagonal's opposite angles are right (cot 0)";
  for (uint32_t e = 0; e < sp.slots.size(); ++e) {
    const bool diagonal = sp.i[e] == 0 && sp.j[e] == 2;
    EXPECT_NEAR(sp.rest_length[e], diagonal ? std::sqrt(2.0) : 1.0 - 0.4, 1e-6) << e;
  }
}

TEST(BuildSprings, PrestretchShortensRestLengthAndRejectsBadValues) {
  Sheet s = square();
  const Springs sp = springs::build_springs(s.particles, s.triangles, {.prestretch = 0.1});
  EXPECT_NEAR(sp.rest_length[0], 0.9, 1e-6);
  EXPECT_THROW(springs::build_springs(s.particles, s.triangles, {.prestretch = 1.0}),
               std::invalid_argument);
  EXPECT_THROW(springs::build_springs(s.particles, s.triangles, {.prestretch = -0.1}),
               std::invalid_argument);
}

// A flat grid of right triangles with alternating diagonals (the rings-and-spokes pattern,
// unrolled) and a jitter: not equilateral anywhere.
Sheet jittered_grid(int n) {
  SurfaceMesh m;
  for (int r = 0; r <= n; ++r) {
    for (int c = 0; c <= n; ++c) {
      const double jx = 0.15 * std::sin(1.7 * r + 2.3 * c), jy = 0.15 * std::cos(2.9 * r - 1.1 * c);
      m.vertices.push_back({c + jx, 1.3 * r + jy, 0.0});
    }
  }
  auto id = [n](int r, int c) { return static_cast<uint32_t>(r * (n + 1) + c); };
  for (int r = 0; r < n; ++r) {
    for (int c = 0; c < n; ++c) {
      if ((r + c) % 2 == 0) {
        m.triangles.push_back({id(r, c), id(r, c + 1), id(r + 1, c + 1)});
        m.triangles.push_back({id(r, c), id(r + 1, c + 1), id(r + 1, c)});
      } else {
        m.triangles.push_back({id(r, c), id(r, c + 1), id(r + 1, c)});
        m.triangles.push_back({id(r, c + 1), id(r + 1, c + 1), id(r + 1, c)});
      }
    }
  }
  return from_mesh(m);
}

// Cotangent pre-tension is the discrete isotropic stress: interior vertices are in equilibrium as
// built. A uniform pre-stretch on the same mesh leaves them unbalanced.
TEST(Pretension, CotangentBalancesInteriorVerticesUniformDoesNot) {
  const int n = 12;
  Sheet s = jittered_grid(n);
  auto max_interior_force = [&](springs::Pretension mode, SpringLaw law) {
    const Springs sp = springs::build_springs(
        s.particles, s.triangles,
        {.law = law, .sheet_modulus_mn_mm = 26.0, .prestretch = 0.03, .pretension = mode});
    Forces f;
    f.resize_zero(s.particles.slots.size());
    springs::add_spring_forces(sp, springs::plan_blocks(sp, s.particles.slots.size()), law,
                               s.particles, f);
    double worst = 0.0;
    for (int r = 1; r < n; ++r) {
      for (int c = 1; c < n; ++c) {
        const uint32_t v = static_cast<uint32_t>(r * (n + 1) + c);
        worst = std::max(worst, static_cast<double>(std::hypot(f.fx[v], f.fy[v])));
      }
    }
    return worst;
  };
  // The tension scale: T0·l ≈ 1.5·0.03·26 mN/mm × 1 mm ≈ 1.2 mN.
  for (SpringLaw law : {SpringLaw::Linear, SpringLaw::Quadratic}) {
    EXPECT_LT(max_interior_force(springs::Pretension::Cotangent, law), 1e-4);
    EXPECT_GT(max_interior_force(springs::Pretension::UniformPrestretch, law), 0.05);
  }
}

TEST(SpringForces, NoForceAtRestAndNewtonsThirdLawUnderLoad) {
  Sheet s = capsule(1);
  for (SpringLaw law : {SpringLaw::Linear, SpringLaw::Quadratic}) {
    const Springs sp = springs::build_springs(s.particles, s.triangles, {.law = law});
    const SpringBlocks blocks = springs::plan_blocks(sp, s.particles.slots.size());
    Forces f;
    f.resize_zero(s.particles.slots.size());
    springs::add_spring_forces(sp, blocks, law, s.particles, f);
    for (uint32_t i = 0; i < s.particles.slots.size(); ++i) ASSERT_NEAR(f.fx[i], 0.0f, 1e-6f);

    Particles moved = s.particles;
    for (uint32_t i = 0; i < moved.slots.size(); ++i)
      moved.z[i] += 0.01f * std::sin(0.37f * static_cast<float>(i));
    f.resize_zero(moved.slots.size());
    springs::add_spring_forces(sp, blocks, law, moved, f);
    double sx = 0, sy = 0, sz = 0, mag = 0;
    for (uint32_t i = 0; i < moved.slots.size(); ++i) {
      sx += f.fx[i], sy += f.fy[i], sz += f.fz[i];
      mag += std::fabs(f.fz[i]);
    }
    EXPECT_GT(mag, 1e-3);
    EXPECT_NEAR(sx, 0.0, 1e-5 * mag);
    EXPECT_NEAR(sy, 0.0, 1e-5 * mag);
    EXPECT_NEAR(sz, 0.0, 1e-5 * mag);
  }
}

// The force is minus the gradient of spring_energy: central differences on a few coordinates.
TEST(SpringForces, ForceIsMinusEnergyGradient) {
  Sheet s = capsule(0);
  for (SpringLaw law : {SpringLaw::Linear, SpringLaw::Quadratic}) {
    const Springs sp =
        springs::build_springs(s.particles, s.triangles, {.law = law, .prestretch = 0.05});
    const SpringBlocks blocks = springs::plan_blocks(sp, s.particles.slots.size());
    Particles p = s.particles;
    for (uint32_t i = 0; i < p.slots.size(); ++i)
      p.x[i] += 0.02f * std::cos(1.3f * static_cast<float>(i));
    Forces f;
    f.resize_zero(p.slots.size());
    springs::add_spring_forces(sp, blocks, law, p, f);
    for (uint32_t v : {5u, 100u, 400u}) {
      const float h = 1e-3f;
      const float x0 = p.x[v];
      p.x[v] = x0 + h;
      const double e_plus = springs::spring_energy(sp, law, p);
      p.x[v] = x0 - h;
      const double e_minus = springs::spring_energy(sp, law, p);
      p.x[v] = x0;
      const double grad = (e_plus - e_minus) / (2.0 * h);
      EXPECT_NEAR(-grad, f.fx[v], 2e-3 * std::max(1.0, std::fabs(grad))) << "vertex " << v;
    }
  }
}

TEST(SpringBlocks, EverySpringStaysInItsBlockOrTheNext) {
  Sheet s = capsule(3);
  const Springs sp = springs::build_springs(s.particles, s.triangles, {});
  const SpringBlocks b = springs::plan_blocks(sp, s.particles.slots.size(), 64);
  ASSERT_GT(b.count(), 2u) << "the capsule's ring order allows a parallel partition";
  EXPECT_EQ(b.particle_begin.front(), 0u);
  EXPECT_EQ(b.particle_begin.back(), s.particles.slots.size());
  EXPECT_EQ(b.spring_begin.back(), sp.slots.size());
  for (uint32_t k = 0; k < b.count(); ++k) {
    const uint32_t end_next = b.particle_begin[std::min<uint32_t>(k + 2, b.count())];
    for (uint32_t e = b.spring_begin[k]; e < b.spring_begin[k + 1]; ++e) {
      ASSERT_GE(sp.i[e], b.particle_begin[k]);
      ASSERT_LT(sp.i[e], b.particle_begin[k + 1]);
      ASSERT_LT(sp.j[e], end_next) << "spring " << e << " reaches past the next block";
    }
  }
}

TEST(SpringBlocks, RejectsUnsortedSprings) {
  Sheet s = square();
  Springs sp = springs::build_springs(s.particles, s.triangles, {});
  std::swap(sp.i[0], sp.i[4]);
  EXPECT_THROW(springs::plan_blocks(sp, 4), std::invalid_argument);
}

std::vector<float> forces_with_threads(int threads, const Sheet& s, const Springs& sp,
                                       const SpringBlocks& b) {
  tbb::global_control limit(tbb::global_control::max_allowed_parallelism,
                            static_cast<size_t>(threads));
  tbb::task_arena arena(threads);
  Forces f;
  f.resize_zero(s.particles.slots.size());
  arena.execute([&] { springs::add_spring_forces(sp, b, SpringLaw::Linear, s.particles, f); });
  std::vector<float> all = f.fx;
  all.insert(all.end(), f.fy.begin(), f.fy.end());
  all.insert(all.end(), f.fz.begin(), f.fz.end());
  return all;
}

TEST(SpringForces, BitIdenticalForOneTwoAndFourThreads) {
  Sheet s = capsule(3);
  for (uint32_t i = 0; i < s.particles.slots.size(); ++i)
    s.particles.z[i] += 0.003f * std::sin(0.1f * i);
  const Springs sp = springs::build_springs(s.particles, s.triangles, {.prestretch = 0.02});
  const SpringBlocks b = springs::plan_blocks(sp, s.particles.slots.size(), 64);
  const auto one = forces_with_threads(1, s, sp, b);
  EXPECT_EQ(one, forces_with_threads(2, s, sp, b));
  EXPECT_EQ(one, forces_with_threads(4, s, sp, b));
}

// Springs appended after the plan (a cut's tail) and tombstones of stiffness 0: the tail runs
// serially after the blocks, so the forces stay bit-identical for any thread count, and they equal
// a fresh plan of the same springs up to float rounding.
TEST(SpringForces, TailAfterThePlanIsBitIdenticalForOneTwoAndFourThreads) {
  Sheet s = capsule(3);
  const uint32_t n = s.particles.slots.size();
  for (uint32_t i = 0; i < n; ++i) s.particles.z[i] += 0.003f * std::sin(0.1f * i);
  Springs sp = springs::build_springs(s.particles, s.triangles, {.prestretch = 0.02});
  const SpringBlocks b = springs::plan_blocks(sp, n, 64);
  for (uint32_t e = 0; e < sp.slots.size();
       e += 7) {  // tombstones, and their pairs again in the tail
    const uint32_t t = table_append(sp, 1);
    sp.i[t] = sp.i[e], sp.j[t] = sp.j[e], sp.rest_length[t] = sp.rest_length[e],
    sp.stiffness[t] = sp.stiffness[e];
    table_remove(sp, e);
    sp.stiffness[e] = 0.0f;
  }
  ASSERT_GT(sp.slots.size(), b.tail_begin());
  const auto one = forces_with_threads(1, s, sp, b);
  EXPECT_EQ(one, forces_with_threads(2, s, sp, b));
  EXPECT_EQ(one, forces_with_threads(4, s, sp, b));
  const Springs fresh = springs::build_springs(s.particles, s.triangles, {.prestretch = 0.02});
  const auto planned = forces_with_threads(1, s, fresh, springs::plan_blocks(fresh, n, 64));
  ASSERT_EQ(one.size(), planned.size());
  for (size_t k = 0; k < one.size(); ++k)
    ASSERT_NEAR(one[k], planned[k], 1e-4f * (1.0f + std::fabs(planned[k])));
}

// Rows patched by added and removed springs, past their room (a row moves), equal a fresh build's
// rows entry for entry (sorted by neighbour); new particles get rows.
TEST(SpringGraph, PatchedRowsEqualAFreshBuild) {
  Sheet s = capsule(0);
  uint32_t n = s.particles.slots.size();
  Springs sp = springs::build_springs(s.particles, s.triangles, {});
  SpringGraph g = springs::build_spring_graph(sp, n);
  std::vector<uint32_t> added, removed;
  for (uint32_t e = 0; e < sp.slots.size(); e += 5) table_remove(sp, e), removed.push_back(e);
  // Six new particles, each joined to particle 0 (whose row overflows its room) and to the
  // previous new one.
  const uint32_t first = n;
  n += 6;
  for (uint32_t a = first; a < n; ++a)
    for (uint32_t b : {0u, a - 1}) {
      if (b == a - 1 && a == first) continue;
      const uint32_t t = table_append(sp, 1);
      sp.i[t] = std::min(a, b), sp.j[t] = std::max(a, b);
      added.push_back(t);
    }
  const uint32_t gone = table_append(sp, 1);  // added, then removed before the patch
  sp.i[gone] = 1, sp.j[gone] = 2;
  added.push_back(gone), table_remove(sp, gone), removed.push_back(gone);
  springs::patch_spring_graph(g, sp, n, removed, added);
  const SpringGraph fresh = springs::build_spring_graph(sp, n);
  ASSERT_EQ(g.particle_count(), n);
  for (uint32_t v = 0; v < n; ++v)
    ASSERT_EQ(springs::graph_row(g, v), springs::graph_row(fresh, v)) << v;
  EXPECT_GT(g.row_capacity[0], fresh.row_size[0]) << "particle 0's row moved to a larger room";
}

TEST(Springs, StiffnessOverMassBoundsTheExplicitStep) {
  Sheet s = square();
  for (uint32_t i = 0; i < 4; ++i) s.particles.inv_mass[i] = 0.5f;  // 2 kg each
  const Springs sp = springs::build_springs(s.particles, s.triangles, {.sheet_modulus_mn_mm = 2.0});
  // Vertices 0 and 2 carry three springs of k = 1: Σk/m = 3 / 2.
  EXPECT_NEAR(springs::max_stiffness_over_mass(sp, s.particles), 1.5, 1e-9);
}

}  // namespace
}  // namespace phaco
