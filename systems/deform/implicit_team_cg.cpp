// Implicit Euler's CG for the row-local preconditioners, worked by a team of threads; see
// solve_row_chunked in implicit_solver.hpp.
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
  const BlockPattern& pattern = cache.pattern;
  const Sym3* blocks = cache.system.block.data();
  const PreconditionerState& state = *cache.preconditioner;
  const ImplicitSettings& settings = cache.settings;
  StepSystem& sys = cache.system;
  CgWork& w = cache.cg;
  const uint32_t rows = pattern.rows();
  const size_t size = 3 * size_t(rows);
  // An even number of chunks of equal size (about settings.cg_chunk_rows rows): the caller and the
  // helper start from opposite ends and meet in the middle with equal shares.
  const uint32_t target_rows = std::max(settings.cg_chunk_rows, 1u);
  uint32_t chunks = even_chunk_count(rows, target_rows);
  const uint32_t chunk_rows = std::max(1u, (rows + chunks - 1) / chunks);
  chunks = std::max(1u, (rows + chunk_rows - 1) / chunk_rows);
  const uint64_t max_iterations = uint64_t(std::max(settings.cg_max_iterations, 1));
  const double tolerance2 = settings.cg_tolerance * settings.cg_tolerance;

  sys.dv = sys.guess;
  for (std::vector<double>* v : {&w.residual, &w.preconditioned, &w.direction, &w.product})
    v->resize(size);
  for (std::vector<double>* v :
       {&w.rhs_norm2, &w.residual_norm2, &w.direction_product, &w.rz[0], &w.rz[1]})
    v->assign(chunks, 0.0);
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
    const uint32_t begin = chunk * chunk_rows, end = std::min(rows, begin + chunk_rows);
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

  const uint64_t stopped = team.run(chunks, 2 + 2 * max_iterations, gate, work);

  const double rhs_norm2 = sum(w.rhs_norm2);
  ImplicitStats& stats = cache.stats;
  if (rhs_norm2 == 0.0) {  // b = 0: Δv = 0 (Eigen's answer)
    sys.dv.setZero();
    stats.cg_iterations = 0, stats.cg_residual = 0.0, stats.cg_converged = true;
    return;
  }
  // Stopped before the direction of iteration i: i − 1 updates of p after the first (Eigen's
  // count), or i at the iteration limit.
  const PhaseOf at = phase_of(stopped);
  stats.cg_iterations = at.iteration >= max_iterations ? static_cast<int>(max_iterations)
                        : at.iteration == 0            ? 0
                                                       : static_cast<int>(at.iteration - 1);
  stats.cg_residual = std::sqrt(sum(w.residual_norm2) / rhs_norm2);
  stats.cg_converged = stats.cg_residual <= settings.cg_tolerance;
}

}  // namespace phaco::deform::implicit_detail
