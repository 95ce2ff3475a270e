// Implicit Euler's linear solve (systems/deform/implicit_solver.hpp): every preconditioner solves a
// stiff, anisotropic membrane system to the tolerance and agrees with a direct solve; the stronger
// ones need fewer CG iterations than Jacobi; factorisations are rebuilt only with the pattern; the
// threaded product and preconditioners give the serial bits.
#include <gtest/gtest.h>
#include <oneapi/tbb/task_arena.h>

#include <Eigen/SparseCholesky>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>

#include "systems/active_nodes/active_nodes.hpp"
#include "systems/deform/implicit_solver.hpp"
#include "tests/systems/deform/implicit_fixtures.hpp"

namespace phaco {
namespace {

using deform::ImplicitCache;
using deform::Preconditioner;
using implicit_test::Body;

constexpr double kFrameStep = 1.0 / 120.0;
constexpr Preconditioner kAll[] = {
    Preconditioner::Jacobi,   Preconditioner::BlockJacobi, Preconditioner::IncompleteCholesky,
    Preconditioner::TwoLevel, Preconditioner::Deflation,   Preconditioner::Balancing};

// The capsule's sheet (E·h = 26 mN/mm) pre-stretched 2 %, pinned at the rim, under gravity: in
// plane the springs' full stiffness, out of plane only the tension (≈ 50× softer), and the mass
// term is ~10⁻⁷ of the stiffness one at the frame step, so A is SPD but badly conditioned.
Body stiff_membrane(int n) {
  Body b =
      implicit_test::make_grid(n, 0.1, 1.3e-10, {.sheet_modulus_mn_mm = 26.0, .prestretch = 0.02});
  b.dynamics.gravity_mm_s2 = {0.0f, 0.0f, -9810.0f};
  return b;
}

// One implicit step leaves the step's system A·Δv = b (taken at the state before the step) in the
// cache.
ImplicitCache assembled(Body& b) {
  ImplicitCache cache;
  auto m = b.membrane();
  deform::implicit_euler_step(m, kFrameStep, cache);
  return cache;
}

struct Solved {
  Eigen::VectorXd dv;
  int iterations = 0;
  bool converged = false;
};

Solved solve_from_zero(ImplicitCache& cache, Preconditioner p) {
  cache.settings.preconditioner = p;
  cache.system.guess.setZero(cache.system.rhs.size());
  deform::implicit_detail::update_preconditioner(cache);
  deform::implicit_detail::solve_linear_system(cache);
  return {cache.system.dv, cache.stats.cg_iterations, cache.stats.cg_converged};
}

Eigen::SparseMatrix<double> assembled_matrix(const ImplicitCache& cache) {
  Eigen::SparseMatrix<double, Eigen::RowMajor, int> a;
  deform::implicit_detail::write_matrix_pattern(cache.pattern, a);
  deform::implicit_detail::write_matrix_values(cache.pattern, cache.system.block, a);
  return a;
}

TEST(ImplicitSolver, EveryPreconditionerSolvesToTheToleranceAndAgreesWithADirectSolve) {
  Body b = stiff_membrane(21);
  ImplicitCache cache = assembled(b);
  const Eigen::SparseMatrix<double> a = assembled_matrix(cache);
  const Eigen::VectorXd rhs = cache.system.rhs;
  ASSERT_GT(rhs.norm(), 0.0);
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> direct(a);
  ASSERT_EQ(direct.info(), Eigen::Success);
  ASSERT_GT(direct.vectorD().minCoeff(), 0.0) << "A is SPD";
  const Eigen::VectorXd exact = direct.solve(rhs);
  for (Preconditioner p : kAll) {
    SCOPED_TRACE(std::string(deform::to_string(p)));
    const Solved s = solve_from_zero(cache, p);
    ASSERT_TRUE(s.converged);
    const double residual = (a * s.dv - rhs).norm() / rhs.norm();
    const double error = (s.dv - exact).norm() / exact.norm();
    std::printf("[ figures  ] %s: %d iterations, true residual %.3g, error against LDLT %.3g\n",
                std::string(deform::to_string(p)).c_str(), s.iterations, residual, error);
    EXPECT_LE(residual, 1.5 * cache.settings.cg_tolerance);
    // Error ≤ cond(A)·residual; the membrane's condition number bounds it loosely, but a wrong
    // preconditioner (not SPD, or applied to the wrong vector) gives O(1) here.
    EXPECT_LT(error, 1e-3);
  }
}

TEST(ImplicitSolver, StrongerPreconditionersNeedFewerIterationsThanJacobi) {
  for (int level : {0, 1}) {
    SCOPED_TRACE(level);
    Body b = implicit_test::make_capsule(level, 2000.0, 0.02);
    b.dynamics.gravity_mm_s2 = {0.0f, 0.0f, -9810.0f};
    ImplicitCache cache = assembled(b);
    const int jacobi = solve_from_zero(cache, Preconditioner::Jacobi).iterations;
    for (Preconditioner p :
         {Preconditioner::BlockJacobi, Preconditioner::IncompleteCholesky, Preconditioner::TwoLevel,
          Preconditioner::Deflation, Preconditioner::Balancing}) {
      const Solved s = solve_from_zero(cache, p);
      std::printf("[ figures  ] capsule level %d, %u unknowns: %s %d iterations, jacobi %d\n",
                  level, cache.stats.unknowns, std::string(deform::to_string(p)).c_str(),
                  s.iterations, jacobi);
      EXPECT_TRUE(s.converged);
      EXPECT_LT(s.iterations, jacobi) << deform::to_string(p);
    }
  }
}

// Steps on an unchanged set reuse the factorisations (stale); a cut or a tear rebuilds them.
TEST(ImplicitSolver, FactorisationsAreRebuiltOnlyWithThePatternOrTopology) {
  for (Preconditioner p : {Preconditioner::IncompleteCholesky, Preconditioner::TwoLevel,
                           Preconditioner::Deflation, Preconditioner::Balancing}) {
    SCOPED_TRACE(std::string(deform::to_string(p)));
    Body b = stiff_membrane(15);
    ImplicitCache cache;
    cache.settings.preconditioner = p;
    for (int s = 0; s < 5; ++s) {
      auto m = b.membrane();
      deform::implicit_euler_step(m, kFrameStep, cache);
      EXPECT_TRUE(cache.stats.cg_converged) << "a stale factor still converges";
    }
    EXPECT_EQ(cache.stats.pattern_builds, 1u);
    EXPECT_EQ(cache.stats.preconditioner_builds, 1u);
    cache.invalidate();  // a cut or a tear
    auto m = b.membrane();
    deform::implicit_euler_step(m, kFrameStep, cache);
    EXPECT_EQ(cache.stats.preconditioner_builds, 2u);
  }
}

// A grasp turns one free particle into a scripted one: the unknown set and the pattern change,
// the two-level hierarchy is reused (that unknown simply drops out of P) and CG still converges;
// with a zero rebuild fraction the same change rebuilds it.
TEST(ImplicitSolver, TwoLevelOutlivesSmallChangesOfTheSet) {
  const int n = 15;
  Body b = stiff_membrane(n);
  ImplicitCache cache;
  cache.settings.preconditioner = Preconditioner::TwoLevel;
  auto step = [&] {
    auto m = b.membrane();
    deform::implicit_euler_step(m, kFrameStep, cache);
    EXPECT_TRUE(cache.stats.cg_converged);
  };
  step();
  const uint32_t grasped = (n / 2) * n + n / 2;
  b.particles.kind[grasped] = ParticleKind::Scripted;
  step();
  EXPECT_EQ(cache.stats.pattern_builds, 2u);
  EXPECT_EQ(cache.stats.preconditioner_builds, 1u);
  b.particles.kind[grasped + 1] = ParticleKind::Scripted;  // one more leaves the built set
  cache.settings.two_level_rebuild_fraction = 0.0;
  step();
  EXPECT_EQ(cache.stats.pattern_builds, 3u);
  EXPECT_EQ(cache.stats.preconditioner_builds, 2u);
}

// Deflation starts CG where P₀ᵀ·r₀ = 0; from there its iterates are Balancing's (the symmetric
// coarse–smoother–coarse preconditioner), at about half the cost per iteration.
TEST(ImplicitSolver, DeflationStartsDeflatedAndFollowsBalancing) {
  Body b = implicit_test::make_capsule(1, 2000.0, 0.02);
  b.dynamics.gravity_mm_s2 = {0.0f, 0.0f, -9810.0f};
  ImplicitCache cache = assembled(b);
  const Solved balancing = solve_from_zero(cache, Preconditioner::Balancing);
  const Solved deflation = solve_from_zero(cache, Preconditioner::Deflation);
  std::printf("[ figures  ] capsule level 1: balancing %d iterations, deflation %d\n",
              balancing.iterations, deflation.iterations);
  ASSERT_TRUE(balancing.converged);
  ASSERT_TRUE(deflation.converged);
  EXPECT_LE(std::abs(deflation.iterations - balancing.iterations), 2);
  EXPECT_LT((deflation.dv - balancing.dv).norm(), 1e-4 * balancing.dv.norm());

  // The deflated first guess: every aggregate's residual sums to zero.
  const deform::PreconditionerState& state = *cache.preconditioner;
  cache.system.guess.setZero(cache.system.rhs.size());
  deform::implicit_detail::deflate_guess(cache);
  Eigen::VectorXd r = cache.system.rhs;
  deform::implicit_detail::add_block_product(
      cache.pattern, cache.system.block, cache.system.guess.data(), r.data(), -1.0, cache.settings);
  Eigen::VectorXd per_aggregate = Eigen::VectorXd::Zero(3 * state.aggregates);
  for (uint32_t u = 0; u < cache.pattern.rows(); ++u)
    for (int a = 0; a < 3; ++a)
      per_aggregate[3 * state.aggregate_of_unknown[u] + a] += r[3 * u + a];
  EXPECT_GT(state.aggregates, 10u);
  EXPECT_LT(per_aggregate.norm(), 1e-9 * cache.system.rhs.norm());
}

// A grasp takes a whole patch out of the set: its aggregates empty, the hierarchy is kept (the
// patch is below the rebuild fraction), and the coarse operator stays exact on what is left, so
// both still solve to the tolerance and agree with a direct solve.
TEST(ImplicitSolver, DeflationKeepsItsAggregatesWhenAPatchLeavesTheSet) {
  const int n = 15;
  for (Preconditioner p : {Preconditioner::Deflation, Preconditioner::Balancing}) {
    SCOPED_TRACE(std::string(deform::to_string(p)));
    Body b = stiff_membrane(n);
    ImplicitCache cache;
    cache.settings.preconditioner = p;
    auto step = [&] {
      auto m = b.membrane();
      deform::implicit_euler_step(m, kFrameStep, cache);
      EXPECT_TRUE(cache.stats.cg_converged);
    };
    step();
    for (int y = 5; y < 10; ++y)
      for (int x = 5; x < 10; ++x) b.particles.kind[y * n + x] = ParticleKind::Scripted;
    step();
    EXPECT_EQ(cache.stats.pattern_builds, 2u);
    EXPECT_EQ(cache.stats.preconditioner_builds, 1u) << "25 of 169 unknowns: below the fraction";
    const deform::PreconditionerState& state = *cache.preconditioner;
    EXPECT_NE(std::count(state.members.begin(), state.members.end(), 0u), 0)
        << "an emptied aggregate";
    const Eigen::SparseMatrix<double> a = assembled_matrix(cache);
    const Eigen::VectorXd exact =
        Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>>(a).solve(cache.system.rhs);
    const Solved s = solve_from_zero(cache, p);
    ASSERT_TRUE(s.converged);
    EXPECT_EQ(cache.stats.preconditioner_builds, 1u);
    EXPECT_LE((a * s.dv - cache.system.rhs).norm(), 1.5e-6 * cache.system.rhs.norm());
    EXPECT_LT((s.dv - exact).norm(), 1e-3 * exact.norm());
  }
}

// Threaded settings: every row loop splits into chunks of 16 rows, and the step forms its team
// (assembly and the row-chunked CG) whatever the set's size. The CG's chunks stay as they are:
// they decide the order of its sums, hence its bits (the threads never do).
void thread_everything(ImplicitCache& cache) {
  cache.settings.parallel_min_unknowns = 0;
  cache.settings.parallel_grain_unknowns = 16;
  cache.settings.cg_team_min_rows = 0;
  cache.settings.team_policy = deform::TeamPolicy::Always;
  cache.settings.parallel_grain_rows = 16;
  cache.settings.parallel_grain_springs = 32;
}

TEST(ImplicitSolver, ParallelProductAndPreconditionersGiveTheSerialBits) {
  Body b = implicit_test::make_capsule(1, 2000.0, 0.02);
  b.dynamics.gravity_mm_s2 = {0.0f, 0.0f, -9810.0f};
  ImplicitCache cache = assembled(b);
  const Eigen::Index size = cache.system.rhs.size();
  ASSERT_GT(size, 3000);
  Eigen::VectorXd x(size);
  for (Eigen::Index i = 0; i < size; ++i) x[i] = std::sin(0.37 * double(i)) + 0.01 * double(i % 7);
  tbb::task_arena two(2);
  for (Preconditioner p : kAll) {
    SCOPED_TRACE(std::string(deform::to_string(p)));
    cache.settings.preconditioner = p;
    cache.settings.parallel_min_unknowns = ~0u;  // serial
    deform::implicit_detail::update_preconditioner(cache);
    Eigen::VectorXd serial_y = Eigen::VectorXd::Constant(size, 0.5), serial_z(size);
    deform::implicit_detail::add_block_product(cache.pattern, cache.system.block, x.data(),
                                               serial_y.data(), -0.7, cache.settings);
    deform::implicit_detail::apply_preconditioner(cache, x.data(), serial_z.data());
    thread_everything(cache);
    Eigen::VectorXd parallel_y = Eigen::VectorXd::Constant(size, 0.5), parallel_z(size);
    two.execute([&] {
      deform::implicit_detail::add_block_product(cache.pattern, cache.system.block, x.data(),
                                                 parallel_y.data(), -0.7, cache.settings);
      deform::implicit_detail::apply_preconditioner(cache, x.data(), parallel_z.data());
    });
    EXPECT_EQ(std::memcmp(serial_y.data(), parallel_y.data(), sizeof(double) * size), 0);
    EXPECT_EQ(std::memcmp(serial_z.data(), parallel_z.data(), sizeof(double) * size), 0);
    EXPECT_GT((serial_y.array() - 0.5).abs().maxCoeff(), 0.0) << "the product did something";
    EXPECT_GT(serial_z.cwiseAbs().maxCoeff(), 0.0) << "the preconditioner did something";
  }
}

// Whole steps, threaded or not, on one or two threads: the same state bits.
TEST(ImplicitSolver, StepsAreBitIdenticalOnOneAndTwoThreads) {
  for (Preconditioner p : kAll) {
    SCOPED_TRACE(std::string(deform::to_string(p)));
    uint64_t hashes[3] = {};
    for (int run = 0; run < 3; ++run) {
      Body b = implicit_test::make_capsule(0, 2000.0, 0.02);
      b.dynamics.gravity_mm_s2 = {0.0f, 0.0f, -9810.0f};
      ImplicitCache cache;
      cache.settings.preconditioner = p;
      if (run > 0) thread_everything(cache);  // run 1 threaded on one thread, run 2 on two
      tbb::task_arena arena(run == 2 ? 2 : 1);
      arena.execute([&] {
        for (int s = 0; s < 3; ++s) {
          auto m = b.membrane();
          deform::implicit_euler_step(m, kFrameStep, cache);
        }
      });
      EXPECT_GT(cache.stats.cg_iterations_total, 0u);
      hashes[run] = implicit_test::hash_state(b.particles);
    }
    EXPECT_EQ(hashes[0], hashes[1]);
    EXPECT_EQ(hashes[0], hashes[2]);
  }
}

// The team CGs (Jacobi, block-Jacobi, deflation with the matrix-free operator) are Eigen's CG with
// their vector sums taken in another order: on the same system, from the same guess, they take the
// same number of iterations (give or take rounding at the last one) and reach the same answer, on
// one thread or on a team of two.
TEST(ImplicitSolver, RowChunkedCgFollowsEigensCg) {
  Body b = implicit_test::make_capsule(1, 2000.0, 0.02);
  b.dynamics.gravity_mm_s2 = {0.0f, 0.0f, -9810.0f};
  ImplicitCache cache = assembled(b);
  ASSERT_GT(cache.pattern.rows(), 1000u);
  for (Preconditioner p :
       {Preconditioner::Jacobi, Preconditioner::BlockJacobi, Preconditioner::Deflation}) {
    SCOPED_TRACE(std::string(deform::to_string(p)));
    cache.settings.cg_operator = deform::CgOperator::Assembled;  // Eigen's CG
    deform::implicit_detail::write_matrix_pattern(cache.pattern, cache.system.matrix);
    deform::implicit_detail::write_matrix_values(cache.pattern, cache.system.block,
                                                 cache.system.matrix);
    const Solved eigen = solve_from_zero(cache, p);
    cache.settings.cg_operator = deform::CgOperator::MatrixFree;  // row-chunked
    const Solved chunked = solve_from_zero(cache, p);
    thread_everything(cache);
    tbb::task_arena two(2);
    Solved team;
    two.execute([&] { team = solve_from_zero(cache, p); });
    std::printf("[ figures  ] %s: Eigen %d iterations, row-chunked %d (team of two: %d)\n",
                std::string(deform::to_string(p)).c_str(), eigen.iterations, chunked.iterations,
                team.iterations);
    ASSERT_TRUE(eigen.converged);
    EXPECT_TRUE(chunked.converged);
    EXPECT_LE(std::abs(chunked.iterations - eigen.iterations), 2);
    EXPECT_LT((chunked.dv - eigen.dv).norm(), 1e-4 * eigen.dv.norm());
    EXPECT_EQ(team.iterations, chunked.iterations);
    EXPECT_EQ(std::memcmp(team.dv.data(), chunked.dv.data(), sizeof(double) * team.dv.size()), 0)
        << "a team of two gives the bits of one thread";
    cache.settings = deform::ImplicitSettings{};
  }
}

// The iteration limit stops the team CGs where Eigen's stops, and says they did not converge.
TEST(ImplicitSolver, RowChunkedCgStopsAtTheIterationLimit) {
  for (Preconditioner p : {Preconditioner::BlockJacobi, Preconditioner::Deflation}) {
    SCOPED_TRACE(std::string(deform::to_string(p)));
    Body b = stiff_membrane(21);
    ImplicitCache cache = assembled(b);
    cache.settings.cg_max_iterations = 5;
    const Solved s = solve_from_zero(cache, p);
    EXPECT_EQ(s.iterations, 5);
    EXPECT_FALSE(s.converged);
    EXPECT_TRUE(s.dv.allFinite());
  }
}

// A cut appends particles: the per-particle arrays grow, the unknown set and its pattern stay,
// and the step gives the bits it gives without the new particles.
TEST(ImplicitSolver, AppendedParticlesKeepThePatternAndTheWarmStart) {
  Body with = stiff_membrane(15), without = stiff_membrane(15);
  ImplicitCache grown, plain;
  for (int s = 0; s < 2; ++s) {
    auto mw = with.membrane(), mo = without.membrane();
    deform::implicit_euler_step(mw, kFrameStep, grown);
    deform::implicit_euler_step(mo, kFrameStep, plain);
  }
  const uint32_t n = with.particles.slots.size();
  table_append(with.particles, 3);  // new, massless particles: not unknowns
  for (uint32_t i = n; i < n + 3; ++i) with.particles.kind[i] = ParticleKind::Anchored;
  for (int s = 0; s < 2; ++s) {
    auto mw = with.membrane(), mo = without.membrane();
    deform::implicit_euler_step(mw, kFrameStep, grown);
    deform::implicit_euler_step(mo, kFrameStep, plain);
  }
  EXPECT_EQ(grown.stats.pattern_builds, 1u);
  EXPECT_EQ(grown.unknowns.unknown_of.size(), size_t(n) + 3);
  EXPECT_EQ(grown.unknowns.unknown_of[n], deform::kNotUnknown);
  EXPECT_EQ(grown.stats.cg_iterations_total, plain.stats.cg_iterations_total)
      << "the warm start was kept";
  for (uint32_t i = 0; i < n; ++i) ASSERT_EQ(with.particles.z[i], without.particles.z[i]) << i;
}

}  // namespace
}  // namespace phaco
