#pragma once
// The Eigen side of implicit Euler's linear solve (implicit.hpp): the matrix-free operator over the
// step's block-CSR system, its product specialisation for Eigen::ConjugateGradient, and the CG
// preconditioners. Internal to systems/deform (implicit_euler.cpp and its tests).
//
// Operator. A is stored as 3×3 symmetric blocks on the block-CSR pattern (row u: u and the
// unknowns joined to it by a spring). The product gathers each row, y_u = Σ_w A_uw·x_w, in the
// row's fixed order: rows are independent, so they split over threads (phaco::parallel_for) with
// results bit-identical to the serial loop. It runs serially below
// ImplicitSettings::parallel_min_unknowns: a small active set pays no threading overhead.
//
// Preconditioners (docs/implicit_and_active.md has the measurements). The capsule's system is a
// membrane far stiffer in plane than out of plane (transverse stiffness is only the tension), so a
// scalar diagonal sees neither the per-node orientation nor the long-range coupling:
//   Jacobi              1/diag(A).
//   BlockJacobi         the inverse of each node's 3×3 diagonal block: catches each node's
//                       in-plane / out-of-plane anisotropy, exactly, at the cost of Jacobi.
//   IncompleteCholesky  Eigen::IncompleteCholesky (zero fill) of the assembled A in the unknowns'
//                       own order (sorted particles: mesh-local). Natural order converges faster
//                       than AMD here (level 3 expert: 40.9 against 54.5 iterations per frame).
//   TwoLevel            smoothed aggregation (Tamstorf, Jones & McCormick 2015, "Smoothed
//                       aggregation multigrid for cloth simulation"), one level below the active
//                       set: aggregates of neighbouring nodes (Vaněk's greedy phases over the block
//                       graph), constant near-null space per axis, prolongator smoothed by one
//                       damped block-Jacobi step, Galerkin coarse operator Pᵀ·A·P factorised by
//                       sparse Cholesky; applied as a symmetric cycle (block-Jacobi pre-smooth,
//                       coarse correction, the same post-smooth), so it is SPD and CG stays valid.
//   Deflation           and Balancing: the same kind of two-level method on
//                       unsmoothed aggregates, built to cost little per iteration on the small
//                       active sets (implicit_deflation.cpp): one coarse solve and one pass over
//                       A·P₀ per iteration instead of TwoLevel's three operator products.
// IncompleteCholesky is rebuilt whenever the pattern is (unknown set or topology changed) and
// otherwise reused stale. The active set changes in almost every frame of a capsulorhexis
// (measured: 1010 pattern builds in 1040 frames at level 3), so TwoLevel keys its prolongator by
// particle and is rebuilt only after a topology change (invalidate()) or when more than
// settings.two_level_rebuild_fraction of the unknowns entered or left the set since the build;
// unknowns new since then get no coarse correction, only the smoother. Either way the result stays
// SPD: the cycle's inverse is 2S − S·A·S + (I − S·A)·P·C·Pᵀ·(I − A·S) with S = ω·D⁻¹, SPD while
// ω·ρ(D⁻¹A) < 2 for ANY SPD coarse solve C and any P, stale or partial; so CG converges to the same
// tolerance, only its speed depends on staleness. D (the smoother's blocks) is refreshed every
// step.
#include <Eigen/IterativeLinearSolvers>
#include <Eigen/SparseCholesky>
#include <Eigen/SparseCore>
#include <algorithm>
#include <array>
#include <span>
#include <vector>

#include "systems/deform/implicit.hpp"

namespace phaco {
class PhasedTeam;  // engine/schedule/phased_team.hpp
}  // namespace phaco

namespace phaco::deform::implicit_detail {
class BlockOperator;
}  // namespace phaco::deform::implicit_detail

// Eigen reads an operator's scalar and storage types from its traits.
template <>
struct Eigen::internal::traits<phaco::deform::implicit_detail::BlockOperator>
    : public Eigen::internal::traits<Eigen::SparseMatrix<double>> {};

namespace phaco::deform {

struct PreconditionerState {
  Preconditioner kind = Preconditioner::Jacobi;
  uint64_t built_for_pattern = ~uint64_t(0);  // stats.pattern_builds when factorised
  Eigen::VectorXd inverse_diagonal;           // Jacobi: 3 per unknown
  std::vector<Sym3> inverse_block;            // BlockJacobi and the two-level smoother: per unknown
  Eigen::IncompleteCholesky<double, Eigen::Lower, Eigen::NaturalOrdering<int>> incomplete_cholesky;
  // Two-level: the smoothed prolongator P as 3×3 blocks, row by row over the unknowns it was built
  // on (keyed by particle, so it outlives small changes of the set), the coarse factor, and the
  // damping ω = 4/(3ρ) of the block-Jacobi smoother, ρ ≈ spectral radius of D⁻¹A at the build.
  using Block3 = std::array<double, 9>;        // row-major 3×3
  std::vector<uint32_t> built_particles;       // sorted: the unknowns at the build
  std::vector<uint32_t> p_begin, p_aggregate;  // per built unknown + 1 / per block: CSR of P
  std::vector<Block3> p_block;                 // per block of P
  std::vector<uint32_t> p_row_of_unknown;      // per current unknown: its row of P, or kNotUnknown
  uint64_t built_for_topology = ~uint64_t(0);  // cache.topology_changes at the build
  Eigen::SimplicialLLT<Eigen::SparseMatrix<double>> coarse;
  double smoother_weight = 0.0;
  uint32_t aggregates = 0;
  // Deflation and Balancing (implicit_deflation.cpp): unsmoothed aggregates P₀ keyed by particle
  // (with built_particles, p_row_of_unknown and built_for_topology above), A·P₀ by rows and the
  // coarse operator E = P₀ᵀ·A·P₀, both refreshed every step; E's block pattern is fixed at the
  // build, `coarse` holds its factor.
  std::vector<uint32_t> aggregate_of_built;      // per built unknown
  std::vector<uint32_t> aggregate_of_unknown;    // per current unknown, or kNotUnknown
  std::vector<uint32_t> ap_begin, ap_aggregate;  // per current unknown + 1 / per block: A·P₀ rows
  std::vector<Sym3> ap_block;                    // Σ_{w∈J} A_uw (symmetric: A's blocks are)
  std::vector<uint32_t> ap_slot;                 // scratch: per aggregate, its block in the row
  std::vector<uint32_t> e_begin, e_row;  // per aggregate J + 1 / per block: E's rows I ≤ J, sorted
  std::vector<uint32_t> members;         // per aggregate: today's unknowns in it
  bool coarse_valid = false;             // E factorised (else the smoother alone)
  // E, column-major: the blocks at and above the diagonal, aggregates in AMD's order; its factor;
  // 1 / the diagonal of the factor L.
  Eigen::SparseMatrix<double> coarse_matrix;
  Eigen::SimplicialLLT<Eigen::SparseMatrix<double>, Eigen::Upper, Eigen::NaturalOrdering<int>>
      deflation_factor;
  Eigen::VectorXd coarse_inverse_diagonal;
  std::vector<int> coarse_group_begin;  // columns of L solved together (implicit_deflation.cpp)
  // Scratch of one application (the preconditioner's solve is const in Eigen's interface).
  mutable Eigen::VectorXd residual, coarse_rhs, coarse_solution, coarse_work;
  // The deflated team CG's t = A·D⁻¹·r (implicit_team_cg.cpp), 3 per unknown.
  std::vector<double> smoothed_product;
};

namespace implicit_detail {

// Row u of A·x, s = Σ_w A_uw·x_w over the row's blocks in their fixed order: every product of A
// sums a row this way, so a row's bits never depend on who computes it.
inline void block_row_product(const BlockPattern& pattern, const Sym3* blocks, const double* x,
                              uint32_t u, double s[3]) {
  double s0 = 0.0, s1 = 0.0, s2 = 0.0;
  for (uint32_t b = pattern.row_begin[u]; b < pattern.row_begin[u + 1]; ++b) {
    const Sym3& k = blocks[b];
    const double* xw = x + 3 * size_t(pattern.col[b]);
    s0 += k[0] * xw[0] + k[1] * xw[1] + k[2] * xw[2];
    s1 += k[1] * xw[0] + k[3] * xw[1] + k[4] * xw[2];
    s2 += k[2] * xw[0] + k[4] * xw[1] + k[5] * xw[2];
  }
  s[0] = s0, s[1] = s1, s[2] = s2;
}

// y += alpha·A·x over the pattern's rows; x and y hold 3 per unknown. Parallel above
// settings.parallel_min_unknowns, bit-identical to the serial loop.
void add_block_product(const BlockPattern& pattern, std::span<const Sym3> blocks, const double* x,
                       double* y, double alpha, const ImplicitSettings& settings);

// Writes a block-CSR layout of 3×3 blocks (per block row + 1: first block; per block: its
// column) into a compressed sparse matrix, outer index by outer index: outer 3u + a holds,
// for each block of u in order, the three inner indices 3·col + 0..2. Values are left as they are.
template <class Matrix>
void write_block_layout(std::span<const uint32_t> begin, std::span<const uint32_t> col,
                        Matrix& matrix) {
  const uint32_t n = static_cast<uint32_t>(begin.size() - 1);
  matrix.resize(3 * Eigen::Index(n), 3 * Eigen::Index(n));
  matrix.resizeNonZeros(9 * Eigen::Index(begin[n]));
  int* outer = matrix.outerIndexPtr();
  int* inner = matrix.innerIndexPtr();
  int k = 0;
  for (uint32_t u = 0; u < n; ++u)
    for (int a = 0; a < 3; ++a) {
      outer[3 * u + a] = k;
      for (uint32_t b = begin[u]; b < begin[u + 1]; ++b)
        for (int d = 0; d < 3; ++d) inner[k++] = static_cast<int>(3 * col[b]) + d;
    }
  outer[3 * n] = k;
}

// Writes the pattern's scalar layout into `matrix` (once per pattern) / its values (every use).
// Unknown u owns rows 3u..3u+2; scalar row 3u+a holds 3·deg(u) entries, block by block.
void write_matrix_pattern(const BlockPattern& pattern,
                          Eigen::SparseMatrix<double, Eigen::RowMajor, int>& matrix);
void write_matrix_values(const BlockPattern& pattern, std::span<const Sym3> blocks,
                         Eigen::SparseMatrix<double, Eigen::RowMajor, int>& matrix);

// Refreshes the preconditioner for this step's system: diagonal inverses every step; the
// factorisations when the pattern was rebuilt or the choice changed. Writes system.matrix's
// values when a factorisation needs them.
void update_preconditioner(ImplicitCache& cache);

// Step 5 of implicit_euler_step: preconditioned CG on A·Δv = b (system.rhs) from system.guess to
// ‖A·Δv − b‖ ≤ settings.cg_tolerance·‖b‖ (Eigen's criterion), with the operator and preconditioner
// the settings choose; writes system.dv and the CG fields of stats (not the totals). Call
// update_preconditioner first.
// `team`: the team the step formed before its assembly (implicit_euler.cpp); without one, the
// row-chunked CG forms its own.
void solve_linear_system(ImplicitCache& cache, PhasedTeam* team = nullptr);

// z = B⁻¹·r, B the cache's preconditioner.
void apply_preconditioner(const ImplicitCache& cache, const double* r, double* z);

// y_u = w·D_u⁻¹·r_u per unknown (block inverse), or y_u += w·D_u⁻¹·r_u.
void apply_block_inverse(std::span<const Sym3> inverse, const double* r, double* y, double w,
                         bool accumulate, const ImplicitSettings& settings);

// Aggregates of the block graph, aggregate_of per unknown; returns their count. Deterministic
// (nodes in index order). Vaněk, Mandel & Brezina 1996: a node whose neighbours are all free seeds
// an aggregate of itself and them; then, with leftover_size 0, leftovers join a neighbouring
// aggregate and what is still left forms its own (TwoLevel); otherwise each leftover forms an
// aggregate with its free neighbours, at most leftover_size nodes (Deflation, Balancing: smaller
// aggregates, a better unsmoothed coarse space).
uint32_t aggregate(const BlockPattern& pattern, std::vector<uint32_t>& aggregate_of,
                   uint32_t leftover_size = 0);

// Row u of A·P₀, P₀ the aggregates' constants (aggregate_of per unknown, kNotUnknown: in none):
// appends, per aggregate J of u's neighbours in first-seen order, J to `aggregates` and
// Σ_{w∈J} A_uw to `sums`. `slot` (per aggregate, all kNotUnknown) is left as it was found.
void sum_row_by_aggregate(const BlockPattern& pattern, const Sym3* blocks,
                          std::span<const uint32_t> aggregate_of, uint32_t u,
                          std::vector<uint32_t>& slot, std::vector<uint32_t>& aggregates,
                          std::vector<Sym3>& sums);

// Maps today's unknowns to the rows of the hierarchy built earlier (state.built_particles) into
// state.p_row_of_unknown; returns how many unknowns entered or left the set since the build.
size_t map_built_rows(const ImplicitCache& cache, PreconditionerState& state);

// Deflation and Balancing (implicit_deflation.cpp): rebuild the aggregates when the set moved on
// or the topology changed, refresh A·P₀ and E = P₀ᵀ·A·P₀ and refactor E (every step); apply.
void update_deflation(ImplicitCache& cache);
void apply_deflation(const ImplicitCache& cache, const double* r, double* z);
// Deflation's CG must start with P₀ᵀ·r₀ = 0: x₀ += P₀·E⁻¹·P₀ᵀ·(b − A·x₀) (system.guess).
void deflate_guess(ImplicitCache& cache);
// The deflated team CG's coarse step (implicit_team_cg.cpp), serial between its phases: e =
// E⁻¹·P₀ᵀ·t into state.coarse_solution, the restriction summed over the unknowns in index order
// (fixed, whoever runs it). With r: returns (P₀ᵀ·r)·e, what r·z₁ must lose to be r·z for
// z = z₁ − P₀·e. Nothing (and 0) without a coarse factor.
double deflation_coarse_step(const ImplicitCache& cache, const double* t, const double* r);
// Rows [begin, end): y += y_sign·P₀·e and ay −= (A·P₀)·e, e = state.coarse_solution; nothing
// without a coarse factor. Row-local: chunks of rows run on any thread with the same bits.
void add_coarse_correction(const PreconditionerState& state, uint32_t begin, uint32_t end,
                           double y_sign, double* y, double* ay);

// An even number of chunks of about target_rows rows each (at least one): a PhasedTeam's two
// threads start from opposite ends and meet in the middle with equal shares.
inline uint32_t even_chunk_count(uint32_t rows, uint32_t target_rows) {
  target_rows = std::max(target_rows, 1u);
  const uint32_t chunks = std::max(1u, (rows + target_rows - 1) / target_rows);
  return chunks > 1 && chunks % 2 == 1 ? chunks + 1 : chunks;
}

// Whether the step's solve runs on its team with the matrix-free operator: the row-local
// preconditioners (Jacobi, block-Jacobi) as solve_row_chunked, Deflation as solve_deflated_team;
// the others (and the assembled operator) in Eigen's CG.
bool team_cg_preconditioner(Preconditioner p);

// Step 5 for a row-local preconditioner and the matrix-free operator: Eigen's preconditioned CG
// (same iterates, same stopping rule, same iteration count), worked in chunks of
// settings.cg_chunk_rows rows by a team of threads (engine/schedule/phased_team.hpp). Each
// iteration is three phases: q = A·p with p·q; the updates of x and r, z = B⁻¹·r with r·r and r·z;
// p = z + β·p. Dot products are summed per chunk and the chunks in order, so the bits are the
// same on any thread count (but not Eigen's, whose dot products sum in another order).
void solve_row_chunked(ImplicitCache& cache, PhasedTeam& team);

// Step 5 for Deflation and the matrix-free operator: the same CG as Eigen's on A-DEF2
// (implicit_deflation.cpp: deflated first guess, z = (I − Q·A)·D⁻¹·r), on the team in row chunks.
// Three phases an iteration: t = A·z₁ (z₁ = D⁻¹·r); z = z₁ − P₀·e and A·z = t − (A·P₀)·e, then
// p and q; the updates of x and r and z₁. Between the first two, one thread restricts t and solves
// E·e = P₀ᵀ·t (small: a few hundred rows). Sums per chunk, then in chunk order: the same bits on
// any thread count.
void solve_deflated_team(ImplicitCache& cache, PhasedTeam& team);

// Matrix-free A over the cache's blocks (Eigen's documented matrix-free pattern: an EigenBase with
// a custom GEMV product, specialised below).
class BlockOperator : public Eigen::EigenBase<BlockOperator> {
 public:
  using Scalar = double;
  using RealScalar = double;
  using StorageIndex = int;
  enum {
    ColsAtCompileTime = Eigen::Dynamic,
    MaxColsAtCompileTime = Eigen::Dynamic,
    IsRowMajor = false
  };

  explicit BlockOperator(const ImplicitCache& cache)
      : cache_(&cache), size_(static_cast<Eigen::Index>(3 * cache.pattern.rows())) {}
  Eigen::Index rows() const { return size_; }
  Eigen::Index cols() const { return size_; }

  template <class Rhs>
  Eigen::Product<BlockOperator, Rhs, Eigen::AliasFreeProduct> operator*(
      const Eigen::MatrixBase<Rhs>& x) const {
    return Eigen::Product<BlockOperator, Rhs, Eigen::AliasFreeProduct>(*this, x.derived());
  }
  // dst += alpha·A·x (dst and x are CG's contiguous work vectors).
  template <class Dst, class Rhs>
  void add_product(Dst& dst, const Rhs& x, double alpha) const {
    const Eigen::Ref<const Eigen::VectorXd> xr(x);
    Eigen::Ref<Eigen::VectorXd> yr(dst);
    add_block_product(cache_->pattern, cache_->system.block, xr.data(), yr.data(), alpha,
                      cache_->settings);
  }

 private:
  const ImplicitCache* cache_;
  Eigen::Index size_;
};

// The cache's preconditioner in the shape Eigen's CG expects. Deriving from SparseSolverBase makes
// solve() an expression that CG evaluates straight into its work vector: no allocation per
// iteration.
class CachePreconditioner : public Eigen::SparseSolverBase<CachePreconditioner> {
 public:
  using Scalar = double;
  using RealScalar = double;
  using StorageIndex = int;
  enum { ColsAtCompileTime = Eigen::Dynamic, MaxColsAtCompileTime = Eigen::Dynamic };

  CachePreconditioner() = default;
  template <class M>
  explicit CachePreconditioner(const M&) {}
  template <class M>
  CachePreconditioner& analyzePattern(const M&) {
    return *this;
  }
  template <class M>
  CachePreconditioner& factorize(const M&) {
    return *this;
  }
  template <class M>
  CachePreconditioner& compute(const M&) {
    return *this;
  }
  Eigen::ComputationInfo info() const { return Eigen::Success; }
  void set(const ImplicitCache* cache) {
    cache_ = cache;
    m_isInitialized = true;
  }
  Eigen::Index rows() const {
    return cache_ ? static_cast<Eigen::Index>(3 * cache_->pattern.rows()) : 0;
  }
  Eigen::Index cols() const { return rows(); }

  template <class Rhs, class Dest>
  void _solve_impl(const Rhs& b, Dest& x) const {
    x.resize(b.rows());
    const Eigen::Ref<const Eigen::VectorXd> br(b);
    Eigen::Ref<Eigen::VectorXd> xr(x);
    apply_preconditioner(*cache_, br.data(), xr.data());
  }

 private:
  const ImplicitCache* cache_ = nullptr;
};

}  // namespace implicit_detail
}  // namespace phaco::deform

namespace Eigen::internal {

template <class Rhs>
struct generic_product_impl<phaco::deform::implicit_detail::BlockOperator, Rhs, SparseShape,
                            DenseShape, GemvProduct>
    : generic_product_impl_base<
          phaco::deform::implicit_detail::BlockOperator, Rhs,
          generic_product_impl<phaco::deform::implicit_detail::BlockOperator, Rhs>> {
  template <class Dest>
  static void scaleAndAddTo(Dest& dst, const phaco::deform::implicit_detail::BlockOperator& lhs,
                            const Rhs& rhs, const double& alpha) {
    lhs.add_product(dst, rhs, alpha);
  }
};

}  // namespace Eigen::internal
