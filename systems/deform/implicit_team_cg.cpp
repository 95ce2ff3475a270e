// Implicit Euler's CG worked by a team of threads: for the row-local preconditioners and for
// deflation; see solve_row_chunked and solve_deflated_team in implicit_solver.hpp.
//
// Why not Eigen's CG here: at level 8 a capsulorhexis frame is ~80 % CG over an active set of a
// few hundred nodes (~16 µs per iteration). Eigen runs the iteration's dot products and vector
// updates on one thread, and a parallel product alone costs a fork and a join per iteration. Here
// one team works all iterations, phase by phase (engine/schedule/phased_team.hpp), and each phase
// fuses what touches the same rows.
//
// Two phases per iteration, not Eigen's three passes: the product is carried by linearity,
// q = A·p = A·z + β·q, so that p and q are updated row by row in the same phase as A·z (Eigen
// forms p = z + β·p first, and a row's product needs its neighbours' p: one more phase).
//   0        r = b − A·x, z = B⁻¹·r                               partial sums of b·b, r·r, r·z
//   1 + 2i   t = A·z; p = z + β·p, q = t + β·q (i = 0: p = z, q = t)   p·q
//   2 + 2i   α = r·z / p·q; x += α·p; r −= α·q; z = B⁻¹·r               r·r, r·z
// with β = r·z(i) / r·z(i − 1). Stops (Eigen's rule): before phase 1 if b = 0 or
// r·r < tol²·b·b already; before 1 + 2i (i ≥ 1) if r·r < tol²·b·b, or when i reaches the
// iteration limit. Iterations are counted as Eigen counts them (updates of p after the first).
//
// Deflation (A-DEF2, implicit_deflation.cpp) is not row-local: z = z₁ − P₀·e with z₁ = D⁻¹·r and
// e = E⁻¹·P₀ᵀ·A·z₁ couples every row to its aggregate's. So A·z₁ gets a phase of its own, and the
// coarse step (restrict A·z₁, solve E, both small and in a fixed order) runs on one thread in the
// gate between that phase and the next; the product A·z = A·z₁ − (A·P₀)·e and z are then row-local
// again, and p, q follow as above:
//   0        r = b − A·x                                         b·b
//   (gate)   e = E⁻¹·P₀ᵀ·r
//   1        x += P₀·e, r −= (A·P₀)·e (the deflated start), z₁ = D⁻¹·r   r·r, r·z₁
//   2 + 3i   t = A·z₁
//   (gate)   e = E⁻¹·P₀ᵀ·t; r·z = r·z₁ − (P₀ᵀ·r)·e
//   3 + 3i   z = z₁ − P₀·e, A·z = t − (A·P₀)·e; p = z + β·p, q = A·z + β·q   p·q
//   4 + 3i   x += α·p; r −= α·q; z₁ = D⁻¹·r                              r·r, r·z₁
// with the same stopping rule before each 2 + 3i. Eigen's CG on the same preconditioner takes
// the same steps; its sums run in another order (and it left the second thread idle).
#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <limits>

#include "engine/schedule/phased_team.hpp"
#include "systems/deform/implicit_solver.hpp"

namespace phaco::deform::implicit_detail {

namespace {

// z = B⁻¹·r over rows [begin, end), B row-local (Jacobi or block-Jacobi).
void precondition_rows(const PreconditionerState& state, const double* r, double* z, uint32_t begin,
                       uint32_t end) {
  if (state.kind == Preconditioner::Jacobi) {
    for (size_t i = 3 * size_t(begin); i < 3 * size_t(end); ++i)
      z[i] = state.inverse_diagonal[Eigen::Index(i)] * r[i];
    return;
  }
  for (uint32_t u = begin; u < end; ++u) {
    const Sym3& k = state.inverse_block[u];
    const double* ru = r + 3 * size_t(u);
    double* zu = z + 3 * size_t(u);
    zu[0] = k[0] * ru[0] + k[1] * ru[1] + k[2] * ru[2];
    zu[1] = k[1] * ru[0] + k[3] * ru[1] + k[4] * ru[2];
    zu[2] = k[2] * ru[0] + k[4] * ru[1] + k[5] * ru[2];
  }
}

// Chunk partials summed in chunk order: the same bits whoever computed which chunk.
double sum(const std::vector<double>& parts) {
  double s = 0.0;
  for (double v : parts) s += v;
  return s;
}

// Chunks of a solve: an even number of equal ones (about settings.cg_chunk_rows rows), fixed by
// the row count alone; the caller and the helper start from opposite ends and meet in the middle.
struct TeamCgChunks {
  uint32_t chunks, chunk_rows;
  uint32_t begin(uint32_t c, uint32_t rows) const { return std::min(rows, c * chunk_rows); }
  uint32_t end(uint32_t c, uint32_t rows) const { return std::min(rows, (c + 1) * chunk_rows); }
};

TeamCgChunks team_cg_chunks(uint32_t rows, const ImplicitSettings& settings) {
  const uint32_t target_rows = std::max(settings.cg_chunk_rows, 1u);
  const uint32_t chunks = even_chunk_count(rows, target_rows);
  const uint32_t chunk_rows = std::max(1u, (rows + chunks - 1) / chunks);
  return {std::max(1u, (rows + chunk_rows - 1) / chunk_rows), chunk_rows};
}

// Sizes the work vectors (3 per row) and zeroes the per-chunk partials.
void prepare_team_cg_work(CgWork& w, size_t size, uint32_t chunks) {
  for (std::vector<double>* v : {&w.residual, &w.preconditioned, &w.direction, &w.product})
    v->resize(size);
  for (std::vector<double>* v :
       {&w.rhs_norm2, &w.residual_norm2, &w.direction_product, &w.rz[0], &w.rz[1]})
    v->assign(chunks, 0.0);
}

// The CG fields of stats once the team stopped before the direction of iteration `iteration`:
// iteration − 1 updates of p after the first (Eigen's count), or the limit when it was reached.
void finish_team_cg_stats(ImplicitCache& cache, uint64_t iteration, uint64_t max_iterations) {
  const CgWork& w = cache.cg;
  const double rhs_norm2 = sum(w.rhs_norm2);
  ImplicitStats& stats = cache.stats;
  if (rhs_norm2 == 0.0) {  // b = 0: Δv = 0 (Eigen's answer)
    cache.system.dv.setZero();
    stats.cg_iterations = 0, stats.cg_residual = 0.0, stats.cg_converged = true;
    return;
  }
  stats.cg_iterations = iteration >= max_iterations ? static_cast<int>(max_iterations)
                        : iteration == 0            ? 0
                                                    : static_cast<int>(iteration - 1);
  stats.cg_residual = std::sqrt(sum(w.residual_norm2) / rhs_norm2);
  stats.cg_converged = stats.cg_residual <= cache.settings.cg_tolerance;
}

// What both team CGs start from: the system, the chunks, the stopping rule; x = the guess, the
// work vectors sized.
struct TeamCgStart {
  const BlockPattern& pattern;
  const Sym3* blocks;
  const PreconditionerState& state;
  StepSystem& sys;
  CgWork& w;
  uint32_t rows;
  TeamCgChunks layout;
  uint64_t max_iterations;
  double tolerance2;
};

TeamCgStart start_team_cg(ImplicitCache& cache) {
  const ImplicitSettings& settings = cache.settings;
  const uint32_t rows = cache.pattern.rows();
  const TeamCgChunks layout = team_cg_chunks(rows, settings);
  cache.system.dv = cache.system.guess;
  prepare_team_cg_work(cache.cg, 3 * size_t(rows), layout.chunks);
  return {cache.pattern,
          cache.system.block.data(),
          *cache.preconditioner,
          cache.system,
          cache.cg,
          rows,
          layout,
          uint64_t(std::max(settings.cg_max_iterations, 1)),
          settings.cg_tolerance * settings.cg_tolerance};
}

enum class Step : uint8_t { Setup, Direction, Update };

struct PhaseOf {
  Step step;
  uint64_t iteration;
};

PhaseOf phase_of(uint64_t phase) {
  if (phase == 0) return {Step::Setup, 0};
  return {(phase - 1) % 2 == 0 ? Step::Direction : Step::Update, (phase - 1) / 2};
}

}  // namespace

void solve_row_chunked(ImplicitCache& cache, PhasedTeam& team) {
  auto [pattern, blocks, state, sys, w, rows, layout, max_iterations, tolerance2] =
      start_team_cg(cache);
  double* x = sys.dv.data();
  const double* b = sys.rhs.data();
  double *r = w.residual.data(), *z = w.preconditioned.data(), *p = w.direction.data(),
         *q = w.product.data();
  const auto threshold = [&w, tolerance2] {
    return std::max(tolerance2 * sum(w.rhs_norm2), std::numeric_limits<double>::min());
  };

  // Read-only over what the earlier phases wrote: every thread asks, all agree.
  const auto gate = [&](uint64_t phase) {
    const PhaseOf at = phase_of(phase);
    if (at.step != Step::Direction) return true;
    if (at.iteration == 0 && sum(w.rhs_norm2) == 0.0) return false;
    return at.iteration < max_iterations && sum(w.residual_norm2) >= threshold();
  };

  // rz[i % 2] holds r·z of iteration i's start (phase 0 or the update before it). Vector sums go
  // through Eigen over the chunk's segment (vectorised; a chunk's segment starts at the same
  // address whoever runs it, so its sum has the same bits).
  using Segment = Eigen::Map<Eigen::VectorXd>;
  const auto work = [&](uint64_t phase, uint32_t chunk) {
    const PhaseOf at = phase_of(phase);
    const uint64_t i = at.iteration;
    const uint32_t begin = layout.begin(chunk, rows), end = layout.end(chunk, rows);
    const Eigen::Index lo = 3 * Eigen::Index(begin), n = 3 * Eigen::Index(end - begin);
    Segment xs(x + lo, n), rs(r + lo, n), zs(z + lo, n), ps(p + lo, n), qs(q + lo, n);
    switch (at.step) {
      case Step::Setup: {
        for (uint32_t u = begin; u < end; ++u) {
          double s[3];
          block_row_product(pattern, blocks, x, u, s);
          for (int a = 0; a < 3; ++a) r[3 * u + a] = b[3 * u + a] - s[a];
        }
        precondition_rows(state, r, z, begin, end);
        w.rhs_norm2[chunk] = Eigen::Map<const Eigen::VectorXd>(b + lo, n).squaredNorm();
        w.residual_norm2[chunk] = rs.squaredNorm();
        w.rz[0][chunk] = rs.dot(zs);
        return;
      }
      case Step::Direction: {
        if (i == 0) {
          for (uint32_t u = begin; u < end; ++u)
            block_row_product(pattern, blocks, z, u, q + 3 * u);
          ps = zs;
        } else {
          // q = A·z + β·q: the product of the new p without a phase of its own (see the top).
          const double beta = sum(w.rz[i % 2]) / sum(w.rz[(i + 1) % 2]);
          for (uint32_t u = begin; u < end; ++u) {
            double t[3];
            block_row_product(pattern, blocks, z, u, t);
            for (int a = 0; a < 3; ++a) q[3 * u + a] = t[a] + beta * q[3 * u + a];
          }
          ps = zs + beta * ps;
        }
        w.direction_product[chunk] = ps.dot(qs);
        return;
      }
      case Step::Update: {
        const double alpha = sum(w.rz[i % 2]) / sum(w.direction_product);
        xs += alpha * ps;
        rs -= alpha * qs;
        precondition_rows(state, r, z, begin, end);
        w.residual_norm2[chunk] = rs.squaredNorm();
        w.rz[(i + 1) % 2][chunk] = rs.dot(zs);
        return;
      }
    }
  };

  const uint64_t stopped = team.run(layout.chunks, 2 + 2 * max_iterations, gate, work);
  finish_team_cg_stats(cache, phase_of(stopped).iteration, max_iterations);
}

void solve_deflated_team(ImplicitCache& cache, PhasedTeam& team) {
  auto [pattern, blocks, state, sys, w, rows, layout, max_iterations, tolerance2] =
      start_team_cg(cache);
  // z holds z₁ = D⁻¹·r until the direction phase makes it z; product holds q = A·p; rz[0] the
  // chunks' r·z₁.
  std::vector<double>& smoothed_product = cache.preconditioner->smoothed_product;
  smoothed_product.resize(3 * size_t(rows));
  double* x = sys.dv.data();
  const double* b = sys.rhs.data();
  double *r = w.residual.data(), *z = w.preconditioned.data(), *p = w.direction.data(),
         *q = w.product.data(), *t = smoothed_product.data();
  double rz[2] = {0.0, 0.0};  // r·z of iteration i at rz[i % 2], written by the coarse gate

  // Phase k ≥ 2: iteration (k − 2) / 3, step (k − 2) % 3: 0 the product, 1 the direction, 2 the
  // update.
  const auto iteration_of = [](uint64_t phase) { return (phase - 2) / 3; };
  const auto gate = [&](uint64_t phase) {
    if (phase == 1) {  // the deflated start: e = E⁻¹·P₀ᵀ·(b − A·x₀)
      if (sum(w.rhs_norm2) == 0.0) return false;
      deflation_coarse_step(cache, r, nullptr);
      return true;
    }
    const uint64_t i = iteration_of(phase);
    switch ((phase - 2) % 3) {
      case 0:
        return i < max_iterations &&
               sum(w.residual_norm2) >=
                   std::max(tolerance2 * sum(w.rhs_norm2), std::numeric_limits<double>::min());
      case 1:
        rz[i % 2] = sum(w.rz[0]) - deflation_coarse_step(cache, t, r);
        return true;
      default:
        return true;
    }
  };

  using Segment = Eigen::Map<Eigen::VectorXd>;
  const auto work = [&](uint64_t phase, uint32_t chunk) {
    const uint32_t begin = layout.begin(chunk, rows), end = layout.end(chunk, rows);
    const Eigen::Index lo = 3 * Eigen::Index(begin), n = 3 * Eigen::Index(end - begin);
    Segment xs(x + lo, n), rs(r + lo, n), zs(z + lo, n), ps(p + lo, n), qs(q + lo, n),
        ts(t + lo, n);
    // z₁ = D⁻¹·r on the chunk, with its r·r and r·z₁.
    const auto smooth = [&] {
      precondition_rows(state, r, z, begin, end);
      w.residual_norm2[chunk] = rs.squaredNorm();
      w.rz[0][chunk] = rs.dot(zs);
    };
    if (phase == 0) {
      for (uint32_t u = begin; u < end; ++u) {
        double s[3];
        block_row_product(pattern, blocks, x, u, s);
        for (int a = 0; a < 3; ++a) r[3 * u + a] = b[3 * u + a] - s[a];
      }
      w.rhs_norm2[chunk] = Eigen::Map<const Eigen::VectorXd>(b + lo, n).squaredNorm();
      return;
    }
    if (phase == 1) {
      add_coarse_correction(state, begin, end, 1.0, x, r);
      smooth();
      return;
    }
    const uint64_t i = iteration_of(phase);
    switch ((phase - 2) % 3) {
      case 0:
        for (uint32_t u = begin; u < end; ++u) block_row_product(pattern, blocks, z, u, t + 3 * u);
        return;
      case 1: {
        add_coarse_correction(state, begin, end, -1.0, z, t);  // z₁ → z, A·z₁ → A·z
        if (i == 0) {
          ps = zs, qs = ts;
        } else {
          const double beta = rz[i % 2] / rz[(i + 1) % 2];
          ps = zs + beta * ps;
          qs = ts + beta * qs;
        }
        w.direction_product[chunk] = ps.dot(qs);
        return;
      }
      default: {
        const double alpha = rz[i % 2] / sum(w.direction_product);
        xs += alpha * ps;
        rs -= alpha * qs;
        smooth();
        return;
      }
    }
  };

  const uint64_t stopped = team.run(layout.chunks, 3 + 3 * max_iterations, gate, work);
  finish_team_cg_stats(cache, stopped < 2 ? 0 : iteration_of(stopped), max_iterations);
}

}  // namespace phaco::deform::implicit_detail
