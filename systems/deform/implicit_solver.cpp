// Implicit Euler's operator product and preconditioners; see implicit_solver.hpp.
#include "systems/deform/implicit_solver.hpp"

#include <Eigen/SparseCore>
#include <algorithm>
#include <array>
#include <cassert>
#include <cmath>
#include <optional>

#include "engine/schedule/parallel.hpp"
#include "engine/schedule/phased_team.hpp"

namespace phaco::deform {

void PreconditionerStateDeleter::operator()(PreconditionerState* p) const {
  delete p;
}

std::string_view to_string(Preconditioner p) {
  switch (p) {
    case Preconditioner::Jacobi:
      return "jacobi";
    case Preconditioner::BlockJacobi:
      return "block_jacobi";
    case Preconditioner::IncompleteCholesky:
      return "incomplete_cholesky";
    case Preconditioner::TwoLevel:
      return "two_level";
    case Preconditioner::Deflation:
      return "deflation";
    case Preconditioner::Balancing:
      return "balancing";
  }
  return "jacobi";
}

std::optional<Preconditioner> parse_preconditioner(std::string_view s) {
  for (Preconditioner p :
       {Preconditioner::Jacobi, Preconditioner::BlockJacobi, Preconditioner::IncompleteCholesky,
        Preconditioner::TwoLevel, Preconditioner::Deflation, Preconditioner::Balancing})
    if (to_string(p) == s) return p;
  return std::nullopt;
}

namespace implicit_detail {

namespace {

// One block per entry of the pattern (a block array of an older pattern would be read past its
// end, or pair blocks with the wrong columns).
[[maybe_unused]] bool blocks_match(const BlockPattern& pattern, std::span<const Sym3> blocks) {
  return blocks.size() == (pattern.row_begin.empty() ? 0 : pattern.row_begin.back()) &&
         pattern.col.size() == blocks.size();
}

inline double sym_at(const Sym3& k, int a, int b) {
  static constexpr int kIndex[3][3] = {{0, 1, 2}, {1, 3, 4}, {2, 4, 5}};
  return k[kIndex[a][b]];
}

// Inverse of a symmetric positive definite 3×3 block by cofactors.
Sym3 inverse_sym(const Sym3& k) {
  const double c00 = k[3] * k[5] - k[4] * k[4], c01 = k[2] * k[4] - k[1] * k[5],
               c02 = k[1] * k[4] - k[2] * k[3];
  const double c11 = k[0] * k[5] - k[2] * k[2], c12 = k[1] * k[2] - k[0] * k[4],
               c22 = k[0] * k[3] - k[1] * k[1];
  const double inv_det = 1.0 / (k[0] * c00 + k[1] * c01 + k[2] * c02);
  return {c00 * inv_det, c01 * inv_det, c02 * inv_det, c11 * inv_det, c12 * inv_det, c22 * inv_det};
}

// Runs fn(row_begin, row_end) over the rows, on several threads only for large row counts. Each
// row's result depends on that row alone, so the split never changes the bits.
template <class Fn>
void for_rows(uint32_t rows, const ImplicitSettings& settings, Fn&& fn) {
  if (rows < settings.parallel_min_unknowns) {
    fn(0u, rows);
    return;
  }
  parallel_for(0u, rows, settings.parallel_grain_unknowns,
               [&fn](uint32_t b, uint32_t e, int) { fn(b, e); });
}

// Spectral radius of D⁻¹A by a few power iterations (an estimate from below; the smoother's
// weight 4/(3ρ) leaves room up to the 2/ρ where damped Jacobi stops converging).
double estimate_spectral_radius(const ImplicitCache& cache, std::span<const Sym3> inverse) {
  const Eigen::Index size = 3 * static_cast<Eigen::Index>(cache.pattern.rows());
  Eigen::VectorXd x(size), ax(size), y(size);
  for (Eigen::Index i = 0; i < size; ++i)
    x[i] = 1.0 + 0.5 * std::sin(0.7 * double(i));  // fixed, not smooth
  double rho = 1.0;
  for (int it = 0; it < 12; ++it) {
    x /= x.norm();
    ax.setZero();
    add_block_product(cache.pattern, cache.system.block, x.data(), ax.data(), 1.0, cache.settings);
    apply_block_inverse(inverse, ax.data(), y.data(), 1.0, false, cache.settings);
    rho = y.norm();
    x.swap(y);
  }
  return rho;
}

// Step 4 for TwoLevel: aggregates, smoothed prolongator and Galerkin coarse operator of today's A.
void build_two_level(const ImplicitCache& cache, PreconditionerState& state) {
  using Block3 = PreconditionerState::Block3;
  const BlockPattern& pattern = cache.pattern;
  const std::span<const Sym3> blocks(cache.system.block);
  const uint32_t n = pattern.rows();
  std::vector<uint32_t> aggregate_of;
  const uint32_t na = aggregate(pattern, aggregate_of);
  state.aggregates = na;
  const double omega = 4.0 / (3.0 * estimate_spectral_radius(cache, state.inverse_block));
  state.smoother_weight = omega;

  // Smoothed prolongator P = (I − ω·D⁻¹·A)·P₀, P₀ = I in block (u, aggregate(u)): the constant
  // near-null space per axis. Row u of P touches the aggregates of u's neighbours:
  // P_uJ = δ(aggregate(u), J)·I − ω·D_u⁻¹·Σ_{w∈J} A_uw.
  std::vector<uint32_t> slot(na, kNotUnknown);
  std::vector<Sym3> sum;  // per aggregate the row touches: Σ_{w∈J} A_uw
  state.p_begin.assign(n + 1, 0);
  state.p_aggregate.clear();
  state.p_block.clear();
  for (uint32_t u = 0; u < n; ++u) {
    const size_t first = state.p_aggregate.size();
    sum_row_by_aggregate(pattern, blocks.data(), aggregate_of, u, slot, state.p_aggregate, sum);
    const Sym3& dinv = state.inverse_block[u];
    for (size_t t = first; t < state.p_aggregate.size(); ++t) {
      const uint32_t agg = state.p_aggregate[t];
      const Sym3& s = sum[t - first];
      Block3 pb;
      for (int a = 0; a < 3; ++a)
        for (int c = 0; c < 3; ++c) {
          double v = 0.0;
          for (int q = 0; q < 3; ++q) v += sym_at(dinv, a, q) * sym_at(s, q, c);
          pb[3 * a + c] = (agg == aggregate_of[u] && a == c ? 1.0 : 0.0) - omega * v;
        }
      state.p_block.push_back(pb);
    }
    sum.clear();
    state.p_begin[u + 1] = static_cast<uint32_t>(state.p_aggregate.size());
  }

  // Galerkin coarse operator A_c = Pᵀ·A·P, lower triangle (all SimplicialLLT reads): row u of A·P
  // gathered per aggregate, then A_c(I, J) += P_uIᵀ·(A·P)_uJ.
  using Triplet = Eigen::Triplet<double>;
  std::vector<Triplet> entries;
  std::vector<uint32_t> touched;
  std::vector<Block3> ap_sum;  // per aggregate the row touches: (A·P)_uJ
  for (uint32_t u = 0; u < n; ++u) {
    touched.clear();
    for (uint32_t b = pattern.row_begin[u]; b < pattern.row_begin[u + 1]; ++b) {
      const uint32_t w = pattern.col[b];
      for (uint32_t pb = state.p_begin[w]; pb < state.p_begin[w + 1]; ++pb) {
        const uint32_t agg = state.p_aggregate[pb];
        if (slot[agg] == kNotUnknown) {
          slot[agg] = static_cast<uint32_t>(touched.size());
          touched.push_back(agg);
          ap_sum.push_back({});
        }
        Block3& s = ap_sum[slot[agg]];
        const Block3& p = state.p_block[pb];
        for (int a = 0; a < 3; ++a)
          for (int c = 0; c < 3; ++c)
            s[3 * a + c] += sym_at(blocks[b], a, 0) * p[c] + sym_at(blocks[b], a, 1) * p[3 + c] +
                            sym_at(blocks[b], a, 2) * p[6 + c];
      }
    }
    for (uint32_t pb = state.p_begin[u]; pb < state.p_begin[u + 1]; ++pb) {
      const uint32_t row_agg = state.p_aggregate[pb];
      const Block3& p = state.p_block[pb];
      for (size_t t = 0; t < touched.size(); ++t) {
        const uint32_t col_agg = touched[t];
        if (col_agg > row_agg) continue;
        const Block3& ap = ap_sum[t];
        for (int a = 0; a < 3; ++a)
          for (int c = 0; c < 3; ++c) {
            if (row_agg == col_agg && c > a) continue;
            const double v = p[a] * ap[c] + p[3 + a] * ap[3 + c] + p[6 + a] * ap[6 + c];
            entries.emplace_back(int(3 * row_agg) + a, int(3 * col_agg) + c, v);
          }
      }
    }
    for (uint32_t agg : touched) slot[agg] = kNotUnknown;
    ap_sum.clear();
  }
  Eigen::SparseMatrix<double> coarse(3 * Eigen::Index(na), 3 * Eigen::Index(na));
  coarse.setFromTriplets(entries.begin(), entries.end());
  state.coarse.compute(coarse);
  state.built_particles = cache.unknowns.particles;
  state.built_for_topology = cache.topology_changes;
  state.coarse_rhs.resize(3 * Eigen::Index(na));
  state.coarse_solution.resize(3 * Eigen::Index(na));
}

}  // namespace

void apply_block_inverse(std::span<const Sym3> inverse, const double* r, double* y, double w,
                         bool accumulate, const ImplicitSettings& settings) {
  for_rows(static_cast<uint32_t>(inverse.size()), settings, [&](uint32_t b, uint32_t e) {
    for (uint32_t u = b; u < e; ++u) {
      const Sym3& k = inverse[u];
      const double r0 = r[3 * u], r1 = r[3 * u + 1], r2 = r[3 * u + 2];
      const double z0 = w * (k[0] * r0 + k[1] * r1 + k[2] * r2);
      const double z1 = w * (k[1] * r0 + k[3] * r1 + k[4] * r2);
      const double z2 = w * (k[2] * r0 + k[4] * r1 + k[5] * r2);
      if (accumulate)
        y[3 * u] += z0, y[3 * u + 1] += z1, y[3 * u + 2] += z2;
      else
        y[3 * u] = z0, y[3 * u + 1] = z1, y[3 * u + 2] = z2;
    }
  });
}

uint32_t aggregate(const BlockPattern& pattern, std::vector<uint32_t>& aggregate_of,
                   uint32_t leftover_size) {
  const uint32_t n = pattern.rows();
  aggregate_of.assign(n, kNotUnknown);
  uint32_t count = 0;
  for (uint32_t u = 0; u < n; ++u) {
    bool free = true;
    for (uint32_t b = pattern.row_begin[u]; b < pattern.row_begin[u + 1] && free; ++b)
      free = aggregate_of[pattern.col[b]] == kNotUnknown;
    if (!free) continue;
    for (uint32_t b = pattern.row_begin[u]; b < pattern.row_begin[u + 1]; ++b)
      aggregate_of[pattern.col[b]] = count;
    ++count;
  }
  if (leftover_size > 0) {  // leftovers group with their free neighbours, up to leftover_size
    for (uint32_t u = 0; u < n; ++u) {
      if (aggregate_of[u] != kNotUnknown) continue;
      aggregate_of[u] = count;
      uint32_t size = 1;
      for (uint32_t b = pattern.row_begin[u]; b < pattern.row_begin[u + 1] && size < leftover_size;
           ++b)
        if (aggregate_of[pattern.col[b]] == kNotUnknown)
          aggregate_of[pattern.col[b]] = count, ++size;
      ++count;
    }
    return count;
  }
  std::vector<uint32_t> joined(aggregate_of);
  for (uint32_t u = 0; u < n; ++u) {
    if (aggregate_of[u] != kNotUnknown) continue;
    for (uint32_t b = pattern.row_begin[u]; b < pattern.row_begin[u + 1]; ++b)
      if (aggregate_of[pattern.col[b]] != kNotUnknown) {
        joined[u] = aggregate_of[pattern.col[b]];
        break;
      }
  }
  aggregate_of.swap(joined);
  for (uint32_t u = 0; u < n; ++u)
    if (aggregate_of[u] == kNotUnknown) aggregate_of[u] = count++;
  return count;
}

void sum_row_by_aggregate(const BlockPattern& pattern, const Sym3* blocks,
                          std::span<const uint32_t> aggregate_of, uint32_t u,
                          std::vector<uint32_t>& slot, std::vector<uint32_t>& aggregates,
                          std::vector<Sym3>& sums) {
  const size_t first = aggregates.size();
  for (uint32_t b = pattern.row_begin[u]; b < pattern.row_begin[u + 1]; ++b) {
    const uint32_t agg = aggregate_of[pattern.col[b]];
    if (agg == kNotUnknown) continue;
    if (slot[agg] == kNotUnknown) {
      slot[agg] = static_cast<uint32_t>(sums.size());
      aggregates.push_back(agg);
      sums.push_back({});
    }
    Sym3& s = sums[slot[agg]];
    for (int a = 0; a < 6; ++a) s[a] += blocks[b][a];
  }
  for (size_t t = first; t < aggregates.size(); ++t) slot[aggregates[t]] = kNotUnknown;
}

size_t map_built_rows(const ImplicitCache& cache, PreconditionerState& state) {
  const std::vector<uint32_t>& now = cache.unknowns.particles;
  const std::vector<uint32_t>& built = state.built_particles;
  state.p_row_of_unknown.assign(now.size(), kNotUnknown);
  size_t matched = 0;
  for (size_t u = 0, r = 0; u < now.size() && r < built.size();) {
    if (now[u] < built[r])
      ++u;
    else if (built[r] < now[u])
      ++r;
    else
      state.p_row_of_unknown[u++] = static_cast<uint32_t>(r++), ++matched;
  }
  return (now.size() - matched) + (built.size() - matched);
}

void add_block_product(const BlockPattern& pattern, std::span<const Sym3> blocks, const double* x,
                       double* y, double alpha, const ImplicitSettings& settings) {
  assert(blocks_match(pattern, blocks));
  for_rows(pattern.rows(), settings, [&](uint32_t begin, uint32_t end) {
    for (uint32_t u = begin; u < end; ++u) {
      double s[3];
      block_row_product(pattern, blocks.data(), x, u, s);
      y[3 * u] += alpha * s[0], y[3 * u + 1] += alpha * s[1], y[3 * u + 2] += alpha * s[2];
    }
  });
}

void write_matrix_pattern(const BlockPattern& pattern,
                          Eigen::SparseMatrix<double, Eigen::RowMajor, int>& matrix) {
  write_block_layout(pattern.row_begin, pattern.col, matrix);
}

void write_matrix_values(const BlockPattern& pattern, std::span<const Sym3> blocks,
                         Eigen::SparseMatrix<double, Eigen::RowMajor, int>& matrix) {
  assert(blocks_match(pattern, blocks) && matrix.rows() == 3 * static_cast<int>(pattern.rows()));
  double* val = matrix.valuePtr();
  const int* outer = matrix.outerIndexPtr();
  for (uint32_t u = 0; u < pattern.rows(); ++u)
    for (int a = 0; a < 3; ++a) {
      double* row = val + outer[3 * u + a];
      for (uint32_t b = pattern.row_begin[u]; b < pattern.row_begin[u + 1]; ++b)
        for (int d = 0; d < 3; ++d) *row++ = sym_at(blocks[b], a, d);
    }
}

void update_preconditioner(ImplicitCache& cache) {
  if (!cache.preconditioner) cache.preconditioner.reset(new PreconditionerState);
  PreconditionerState& state = *cache.preconditioner;
  const BlockPattern& pattern = cache.pattern;
  const uint32_t nu = pattern.rows();
  const Preconditioner kind = cache.settings.preconditioner;
  const std::span<const Sym3> blocks(cache.system.block);

  // Diagonal inverses are fresh every step: O(unknowns), and the smoother needs today's A.
  if (kind == Preconditioner::Jacobi) {
    state.inverse_diagonal.resize(3 * Eigen::Index(nu));
    for (uint32_t u = 0; u < nu; ++u) {
      const Sym3& d = blocks[pattern.diag_pos[u] + pattern.row_begin[u]];
      state.inverse_diagonal[3 * u] = 1.0 / d[0], state.inverse_diagonal[3 * u + 1] = 1.0 / d[3];
      state.inverse_diagonal[3 * u + 2] = 1.0 / d[5];
    }
  } else if (kind != Preconditioner::IncompleteCholesky) {  // block-Jacobi, two-level smoother
    state.inverse_block.resize(nu);
    for (uint32_t u = 0; u < nu; ++u)
      state.inverse_block[u] = inverse_sym(blocks[pattern.diag_pos[u] + pattern.row_begin[u]]);
  }

  const bool kind_changed = state.kind != kind;
  state.kind = kind;
  if (kind == Preconditioner::IncompleteCholesky) {
    // Rebuilt with the pattern (unknown set or topology), otherwise reused stale.
    if (!kind_changed && state.built_for_pattern == cache.stats.pattern_builds) return;
    if (cache.settings.cg_operator != CgOperator::Assembled)
      write_matrix_pattern(pattern, cache.system.matrix);
    write_matrix_values(pattern, blocks, cache.system.matrix);
    const Eigen::SparseMatrix<double> a = cache.system.matrix;  // symmetric: column-major = itself
    state.incomplete_cholesky.compute(a);
    state.built_for_pattern = cache.stats.pattern_builds;
    ++cache.stats.preconditioner_builds;
  } else if (kind == Preconditioner::TwoLevel) {
    // Rebuilt after a topology change or when the set moved on by more than the fraction.
    state.residual.resize(3 * Eigen::Index(nu));
    const bool same_topology = !kind_changed && state.built_for_topology == cache.topology_changes;
    const size_t moved = same_topology ? map_built_rows(cache, state) : ~size_t(0);
    if (same_topology && double(moved) <= cache.settings.two_level_rebuild_fraction * double(nu))
      return;
    build_two_level(cache, state);
    map_built_rows(cache, state);
    ++cache.stats.preconditioner_builds;
  } else if (kind == Preconditioner::Deflation || kind == Preconditioner::Balancing) {
    if (kind_changed) state.built_for_topology = ~uint64_t(0);
    update_deflation(cache);
  }
}

namespace {

template <class Operator>
void solve_with(const Operator& op, ImplicitCache& cache) {
  Eigen::ConjugateGradient<Operator, Eigen::Lower | Eigen::Upper, CachePreconditioner> cg;
  cg.preconditioner().set(&cache);
  cg.setTolerance(cache.settings.cg_tolerance);
  cg.setMaxIterations(std::max(cache.settings.cg_max_iterations, 1));
  cg.compute(op);
  cache.system.dv = cg.solveWithGuess(cache.system.rhs, cache.system.guess);
  cache.stats.cg_iterations = static_cast<int>(cg.iterations());
  cache.stats.cg_residual = cg.error();
  cache.stats.cg_converged = cg.info() == Eigen::Success;
}

}  // namespace

bool team_cg_preconditioner(Preconditioner p) {
  return p == Preconditioner::Jacobi || p == Preconditioner::BlockJacobi ||
         p == Preconditioner::Deflation;
}

void solve_linear_system(ImplicitCache& cache, PhasedTeam* team) {
  const Preconditioner p = cache.settings.preconditioner;
  if (cache.settings.cg_operator == CgOperator::MatrixFree && team_cg_preconditioner(p)) {
    std::optional<PhasedTeam> own;
    if (!team) team = &own.emplace(cache.pattern.rows() >= cache.settings.cg_team_min_rows);
    if (p == Preconditioner::Deflation)
      solve_deflated_team(cache, *team);
    else
      solve_row_chunked(cache, *team);
    return;
  }
  if (cache.settings.preconditioner == Preconditioner::Deflation) deflate_guess(cache);
  if (cache.settings.cg_operator == CgOperator::Assembled)
    solve_with(cache.system.matrix, cache);
  else
    solve_with(BlockOperator(cache), cache);
}

void apply_preconditioner(const ImplicitCache& cache, const double* r, double* z) {
  const PreconditionerState& state = *cache.preconditioner;
  const Eigen::Index size = 3 * static_cast<Eigen::Index>(cache.pattern.rows());
  const ImplicitSettings& settings = cache.settings;
  switch (state.kind) {
    case Preconditioner::Jacobi:
      for (Eigen::Index i = 0; i < size; ++i) z[i] = state.inverse_diagonal[i] * r[i];
      return;
    case Preconditioner::BlockJacobi:
      apply_block_inverse(state.inverse_block, r, z, 1.0, false, settings);
      return;
    case Preconditioner::IncompleteCholesky: {
      Eigen::Map<Eigen::VectorXd>(z, size) =
          state.incomplete_cholesky.solve(Eigen::Map<const Eigen::VectorXd>(r, size));
      return;
    }
    case Preconditioner::Deflation:
    case Preconditioner::Balancing:
      apply_deflation(cache, r, z);
      return;
    case Preconditioner::TwoLevel: {
      // Symmetric two-level cycle: z = S·r; z += P·A_c⁻¹·Pᵀ·(r − A·z); z += S·(r − A·z), S = ω·D⁻¹.
      const std::span<const Sym3> blocks(cache.system.block);
      const double w = state.smoother_weight;
      Eigen::VectorXd& t = state.residual;
      apply_block_inverse(state.inverse_block, r, z, w, false, settings);
      Eigen::Map<Eigen::VectorXd>(t.data(), size) = Eigen::Map<const Eigen::VectorXd>(r, size);
      add_block_product(cache.pattern, blocks, z, t.data(), -1.0, settings);
      // Restriction Pᵀ·t and, after the coarse solve, prolongation, over the rows of P that
      // today's unknowns still have.
      state.coarse_rhs.setZero();
      const uint32_t nu = cache.pattern.rows();
      for (uint32_t u = 0; u < nu; ++u) {
        const uint32_t row = state.p_row_of_unknown[u];
        if (row == kNotUnknown) continue;
        const double* tu = t.data() + 3 * size_t(u);
        for (uint32_t pb = state.p_begin[row]; pb < state.p_begin[row + 1]; ++pb) {
          const PreconditionerState::Block3& p = state.p_block[pb];
          double* c = state.coarse_rhs.data() + 3 * size_t(state.p_aggregate[pb]);
          for (int a = 0; a < 3; ++a) c[a] += p[a] * tu[0] + p[3 + a] * tu[1] + p[6 + a] * tu[2];
        }
      }
      state.coarse_solution = state.coarse.solve(state.coarse_rhs);
      for (uint32_t u = 0; u < nu; ++u) {
        const uint32_t row = state.p_row_of_unknown[u];
        if (row == kNotUnknown) continue;
        double* zu = z + 3 * size_t(u);
        for (uint32_t pb = state.p_begin[row]; pb < state.p_begin[row + 1]; ++pb) {
          const PreconditionerState::Block3& p = state.p_block[pb];
          const double* e = state.coarse_solution.data() + 3 * size_t(state.p_aggregate[pb]);
          for (int a = 0; a < 3; ++a)
            zu[a] += p[3 * a] * e[0] + p[3 * a + 1] * e[1] + p[3 * a + 2] * e[2];
        }
      }
      Eigen::Map<Eigen::VectorXd>(t.data(), size) = Eigen::Map<const Eigen::VectorXd>(r, size);
      add_block_product(cache.pattern, blocks, z, t.data(), -1.0, settings);
      apply_block_inverse(state.inverse_block, t.data(), z, w, true, settings);
      return;
    }
  }
}

}  // namespace implicit_detail
}  // namespace phaco::deform
