// Two-level preconditioners on unsmoothed aggregates, cheap enough per CG iteration for the
// capsule's small active sets; see implicit_solver.hpp and docs/implicit_and_active.md.
//
// The coarse space is P₀: per aggregate (Vaněk's greedy aggregates of the block graph) one
// constant per axis, so restriction P₀ᵀ·r sums an aggregate's rows and prolongation copies a
// coarse value to its members: a vector pass, not an operator product as with the smoothed
// prolongator. The coarse operator E = P₀ᵀ·A·P₀ and A·P₀ (per unknown, one symmetric block per
// neighbouring aggregate) are refreshed from today's A every step, E refactored numerically on a
// block pattern fixed at the build. With Q = P₀·E⁻¹·P₀ᵀ and S = D⁻¹ (block-Jacobi):
//   Deflation  z = (I − Q·A)·S·r (Tang, Nabben, Vuik & Erlangga 2009, "A-DEF2"): one coarse
//              solve and one pass over A·P₀ per iteration. Not symmetric in general, but when
//              CG starts from P₀ᵀ·r₀ = 0 (deflate_guess) every residual keeps P₀ᵀ·r = 0, and on
//              those residuals it equals Balancing below: CG's iterates are Balancing's.
//   Balancing  z = Q·r + (I − Q·A)·S·(I − A·Q)·r ("BNN"; the coarse–smoother–coarse cycle): SPD
//              for any SPD S and E, exact or not; two coarse solves and two passes over A·P₀.
// Both converge like the symmetric smoother–coarse–smoother cycle of TwoLevel with the same
// coarse space (its A-norm contraction equals the coarse–smoother–coarse one's), for about a third
// of its cost per iteration.
// The aggregates are keyed by particle like TwoLevel's prolongator and rebuilt after a topology
// change or when more than settings.two_level_rebuild_fraction of the unknowns entered or left the
// set: a member that left drops out of its aggregate (an emptied aggregate gets E's block I), an
// unknown new since the build belongs to none (only the smoother acts on it); E stays exact.
#include <Eigen/SparseCore>
#include <algorithm>
#include <cassert>

#include "systems/deform/implicit_solver.hpp"

namespace phaco::deform::implicit_detail {

namespace {

constexpr int kMaxGroup = 6;  // columns of the factor solved together at most
// Leftovers of Vaněk's first phase form aggregates of at most this many nodes instead of joining
// a neighbouring aggregate. Measured on the level-3 expert: joining (54 aggregates for ~430
// unknowns) 50.9 CG iterations per stepped frame, own aggregates of ≤ 4 (~150) 36.7.
constexpr uint32_t kLeftoverAggregate = 4;

// E's blocks at and below the diagonal as (column J, row I ≤ J), by J then by I, each once. Each
// aggregate marks the aggregates its members' rows reach and sorts that handful: a sort of every
// block of A instead was most of a rebuild (≈ 0.2 ms of 0.5 at level 6, the expert's cut frames).
// A's pattern is symmetric, so the pairs met from either end are the same.
void list_coarse_pairs(const BlockPattern& pattern, const std::vector<uint32_t>& aggregate_of,
                       uint32_t na, std::vector<std::pair<uint32_t, uint32_t>>& pairs) {
  const uint32_t nu = pattern.rows();
  std::vector<uint32_t> member_begin(na + 1, 0), members(nu), mark(na, kNotUnknown), reached;
  for (uint32_t u = 0; u < nu; ++u) {
    assert(aggregate_of[u] < na);
    ++member_begin[aggregate_of[u] + 1];
  }
  for (uint32_t a = 0; a < na; ++a) member_begin[a + 1] += member_begin[a];
  {
    std::vector<uint32_t> fill(member_begin.begin(), member_begin.end() - 1);
    for (uint32_t u = 0; u < nu; ++u) members[fill[aggregate_of[u]]++] = u;
  }
  pairs.clear();
  for (uint32_t j = 0; j < na; ++j) {
    reached.clear();
    for (uint32_t k = member_begin[j]; k < member_begin[j + 1]; ++k) {
      const uint32_t u = members[k];
      for (uint32_t b = pattern.row_begin[u]; b < pattern.row_begin[u + 1]; ++b) {
        const uint32_t i = aggregate_of[pattern.col[b]];
        if (i <= j && mark[i] != j) mark[i] = j, reached.push_back(i);
      }
    }
    std::sort(reached.begin(), reached.end());
    for (uint32_t i : reached) pairs.emplace_back(j, i);
  }
}

// E's block pattern (blocks at and below the diagonal, by block column) and the scalar matrix
// with that pattern, analysed for the factorisation.
void build_coarse_pattern(const BlockPattern& pattern, PreconditionerState& state) {
  const uint32_t na = state.aggregates;
  std::vector<std::pair<uint32_t, uint32_t>> pairs;  // (column J, row I), I ≤ J
  const auto list_pairs = [&] { list_coarse_pairs(pattern, state.aggregate_of_built, na, pairs); };
  // Number the aggregates in AMD's order of their graph once here, so that E is built already
  // ordered and each step's factorisation reads it in place (no permuted copy, no permutation in
  // the solve).
  list_pairs();
  {
    std::vector<Eigen::Triplet<double>> graph;
    graph.reserve(2 * pairs.size());
    for (const auto& [j, i] : pairs)
      graph.emplace_back(int(i), int(j), 1.0), graph.emplace_back(int(j), int(i), 1.0);
    Eigen::SparseMatrix<double> g(na, na);
    g.setFromTriplets(graph.begin(), graph.end());
    Eigen::PermutationMatrix<Eigen::Dynamic, Eigen::Dynamic, int> order;  // new → old
    Eigen::AMDOrdering<int>()(g, order);
    std::vector<uint32_t> renumber(na);
    for (uint32_t k = 0; k < na; ++k) renumber[uint32_t(order.indices()[k])] = k;
    for (uint32_t& agg : state.aggregate_of_built) agg = renumber[agg];
    list_pairs();
  }
  state.e_begin.assign(na + 1, 0);
  state.e_row.resize(pairs.size());
  for (size_t k = 0; k < pairs.size(); ++k) {
    ++state.e_begin[pairs[k].first + 1];
    state.e_row[k] = pairs[k].second;
  }
  for (uint32_t j = 0; j < na; ++j) state.e_begin[j + 1] += state.e_begin[j];

  // Scalar column 3J + c holds, for each block row I of column J in order (J itself last), rows
  // 3I..3I+2: E's upper triangle, which Eigen's Cholesky reads in place.
  Eigen::SparseMatrix<double>& e = state.coarse_matrix;
  write_block_layout(state.e_begin, state.e_row, e);
  std::fill(e.valuePtr(), e.valuePtr() + e.nonZeros(), 0.0);
  state.deflation_factor.analyzePattern(e);
}

void build_aggregates(const ImplicitCache& cache, PreconditionerState& state) {
  state.aggregates = aggregate(cache.pattern, state.aggregate_of_built, kLeftoverAggregate);
  state.built_particles = cache.unknowns.particles;
  state.built_for_topology = cache.topology_changes;
  build_coarse_pattern(cache.pattern, state);
  state.coarse_rhs.resize(3 * Eigen::Index(state.aggregates));
  state.coarse_solution.resize(3 * Eigen::Index(state.aggregates));
}

// A·P₀ by rows and E = P₀ᵀ·A·P₀ from today's A; false when E needs a block the build's pattern
// lacks (then rebuild).
bool refresh_coarse_operator(const ImplicitCache& cache, PreconditionerState& state) {
  const BlockPattern& pattern = cache.pattern;
  const Sym3* blocks = cache.system.block.data();
  const uint32_t nu = pattern.rows(), na = state.aggregates;
  state.aggregate_of_unknown.resize(nu);
  state.members.assign(na, 0);
  for (uint32_t u = 0; u < nu; ++u) {
    const uint32_t row = state.p_row_of_unknown[u];
    const uint32_t agg = row == kNotUnknown ? kNotUnknown : state.aggregate_of_built[row];
    state.aggregate_of_unknown[u] = agg;
    if (agg != kNotUnknown) ++state.members[agg];
  }

  // Row u of A·P₀: Σ_{w∈J} A_uw per aggregate J of u's neighbours, in first-seen order.
  std::vector<uint32_t>& slot = state.ap_slot;
  slot.assign(na, kNotUnknown);
  state.ap_begin.assign(nu + 1, 0);
  state.ap_aggregate.clear();
  state.ap_block.clear();
  for (uint32_t u = 0; u < nu; ++u) {
    sum_row_by_aggregate(pattern, blocks, state.aggregate_of_unknown, u, slot, state.ap_aggregate,
                         state.ap_block);
    state.ap_begin[u + 1] = static_cast<uint32_t>(state.ap_aggregate.size());
  }

  // E(I, J) = Σ_{u∈I} (A·P₀)_uJ for J ≤ I; an empty aggregate's diagonal block is I (its column
  // of P₀ is zero, so it never couples).
  Eigen::SparseMatrix<double>& e = state.coarse_matrix;
  double* val = e.valuePtr();
  const int* outer = e.outerIndexPtr();
  std::fill(val, val + e.nonZeros(), 0.0);
  static constexpr int kIndex[3][3] = {{0, 1, 2}, {1, 3, 4}, {2, 4, 5}};
  for (uint32_t u = 0; u < nu; ++u) {
    const uint32_t i = state.aggregate_of_unknown[u];
    if (i == kNotUnknown) continue;
    for (uint32_t t = state.ap_begin[u]; t < state.ap_begin[u + 1]; ++t) {
      const uint32_t j = state.ap_aggregate[t];
      if (j < i) continue;
      const auto rows_begin = state.e_row.begin() + state.e_begin[j],
                 rows_end = state.e_row.begin() + state.e_begin[j + 1];
      const auto at = std::lower_bound(rows_begin, rows_end, i);
      if (at == rows_end || *at != i) return false;
      const int k = 3 * int(at - rows_begin);
      for (int c = 0; c < 3; ++c)
        for (int a = 0; a < 3; ++a)
          val[outer[3 * j + c] + k + a] += state.ap_block[t][kIndex[a][c]];
    }
  }
  for (uint32_t j = 0; j < na; ++j) {
    if (state.members[j] != 0) continue;
    const int last = 3 * int(state.e_begin[j + 1] - state.e_begin[j] - 1);  // block (J, J)
    for (int c = 0; c < 3; ++c) val[outer[3 * j + c] + last + c] = 1.0;
  }
  state.deflation_factor.factorize(e);
  if (state.deflation_factor.info() != Eigen::Success) return false;
  const auto& l = state.deflation_factor.matrixL().nestedExpression();
  state.coarse_inverse_diagonal.resize(l.cols());
  for (Eigen::Index j = 0; j < l.cols(); ++j)
    state.coarse_inverse_diagonal[j] = 1.0 / l.valuePtr()[l.outerIndexPtr()[j]];
  return true;
}

// Column groups of E's factor L that share their rows below the group (an aggregate's three axes
// are indistinguishable to AMD, so they come out as neighbouring columns with one pattern): the
// triangular passes then work a group's columns together, independent updates instead of a chain
// of dependent ones. Fixed with the pattern.
void group_factor_columns(PreconditionerState& state) {
  const auto& l =
      state.deflation_factor.matrixL().nestedExpression();  // column-major, diagonal first
  const int* outer = l.outerIndexPtr();
  const int* inner = l.innerIndexPtr();
  const int n = int(l.cols());
  // Columns j .. j + w − 1 form a group when column j + c holds, after its diagonal, the rows
  // j + c + 1 .. j + w − 1 and then exactly column j's rows past j + w − 1.
  const auto is_group = [&](int j, int w) {
    const int below = outer[j + 1] - outer[j] - 1;
    if (j + w > n || below < w - 1) return false;
    const int* tail = inner + outer[j] + w;  // column j's rows past the group
    const int shared = below - (w - 1);
    for (int c = 0; c < w; ++c) {
      const int* rows = inner + outer[j + c] + 1;
      if (outer[j + c + 1] - outer[j + c] - 1 != w - 1 - c + shared) return false;
      for (int c2 = c + 1; c2 < w; ++c2)
        if (rows[c2 - c - 1] != j + c2) return false;
      if (!std::equal(tail, tail + shared, rows + (w - 1 - c))) return false;
    }
    return true;
  };
  state.coarse_group_begin.clear();
  for (int j = 0; j < n;) {
    int w = 1;
    while (w < kMaxGroup && is_group(j, w + 1)) ++w;
    state.coarse_group_begin.push_back(j);
    j += w;
  }
  state.coarse_group_begin.push_back(n);
}

// The triangular passes over one group of W columns j0 .. j0 + W − 1 (W a constant, so that the
// group's values stay in registers). Column j0 + c holds its diagonal, rows j0 + c + 1 ..
// j0 + W − 1, then the group's shared rows from outer[j0 + c] + W − c on.
template <int W>
void forward_group(const int* outer, const int* inner, const double* val, const double* inv_diag,
                   int j0, double* y) {  // L·y' = y
  double x[W];
  const double* l[W];
  for (int c = 0; c < W; ++c) {
    x[c] = y[j0 + c] *= inv_diag[j0 + c];
    for (int c2 = c + 1; c2 < W; ++c2) y[j0 + c2] -= val[outer[j0 + c] + c2 - c] * x[c];
    l[c] = val + outer[j0 + c] + W - c;
  }
  const int shared = outer[j0 + W] - outer[j0 + W - 1] - 1;
  const int* rows = inner + outer[j0 + W - 1] + 1;
  for (int k = 0; k < shared; ++k) {
    double t = 0.0;
    for (int c = 0; c < W; ++c) t += l[c][k] * x[c];
    y[rows[k]] -= t;
  }
}

template <int W>
void backward_group(const int* outer, const int* inner, const double* val, const double* inv_diag,
                    int j0, double* y) {  // Lᵀ·y'' = y'
  double t[W];
  const double* l[W];
  for (int c = 0; c < W; ++c) t[c] = 0.0, l[c] = val + outer[j0 + c] + W - c;
  const int shared = outer[j0 + W] - outer[j0 + W - 1] - 1;
  const int* rows = inner + outer[j0 + W - 1] + 1;
  for (int k = 0; k < shared; ++k) {
    const double yk = y[rows[k]];
    for (int c = 0; c < W; ++c) t[c] += l[c][k] * yk;
  }
  for (int c = W - 1; c >= 0; --c) {
    double x = y[j0 + c] - t[c];
    for (int c2 = c + 1; c2 < W; ++c2) x -= val[outer[j0 + c] + c2 - c] * y[j0 + c2];
    y[j0 + c] = x * inv_diag[j0 + c];
  }
}

// fn.template operator()<W>() for the group's width w (1 .. kMaxGroup).
template <class Fn>
void with_group_width(int w, Fn&& fn) {
  switch (w) {
    case 1:
      return fn.template operator()<1>();
    case 2:
      return fn.template operator()<2>();
    case 3:
      return fn.template operator()<3>();
    case 4:
      return fn.template operator()<4>();
    case 5:
      return fn.template operator()<5>();
    default:
      return fn.template operator()<6>();
  }
}

// coarse_solution = E⁻¹·coarse_rhs through the factor's arrays, group by group. E is small (a few
// hundred rows), and Eigen's solve() spent most of its time around and in the two dependent chains
// of scalar updates (measured: 17 % of the expert's run).
void coarse_solve(const PreconditionerState& state) {
  const auto& l = state.deflation_factor.matrixL().nestedExpression();
  assert(state.deflation_factor.permutationP().size() == 0);  // E is built in AMD's order
  const int* outer = l.outerIndexPtr();
  const int* inner = l.innerIndexPtr();
  const double* val = l.valuePtr();
  const double* inv_diag = state.coarse_inverse_diagonal.data();
  const int n = int(l.cols());
  const std::vector<int>& groups = state.coarse_group_begin;
  Eigen::VectorXd& y = state.coarse_work;
  y.resize(n);
  y = state.coarse_rhs;
  for (size_t g = 0; g + 1 < groups.size(); ++g)
    with_group_width(groups[g + 1] - groups[g], [&]<int W>() {
      forward_group<W>(outer, inner, val, inv_diag, groups[g], y.data());
    });
  for (size_t g = groups.size() - 1; g-- > 0;)
    with_group_width(groups[g + 1] - groups[g], [&]<int W>() {
      backward_group<W>(outer, inner, val, inv_diag, groups[g], y.data());
    });
  state.coarse_solution = y;
}

// c = P₀ᵀ·r: each aggregate sums its members' rows.
void restrict_constant(const PreconditionerState& state, uint32_t nu, const double* r,
                       Eigen::VectorXd& c) {
  c.setZero();
  for (uint32_t u = 0; u < nu; ++u) {
    const uint32_t agg = state.aggregate_of_unknown[u];
    if (agg == kNotUnknown) continue;
    for (int a = 0; a < 3; ++a) c[3 * agg + a] += r[3 * u + a];
  }
}

// z += s·P₀·e: each member gets its aggregate's value.
void prolong_constant(const PreconditionerState& state, uint32_t nu, const Eigen::VectorXd& e,
                      double* z, double s) {
  for (uint32_t u = 0; u < nu; ++u) {
    const uint32_t agg = state.aggregate_of_unknown[u];
    if (agg == kNotUnknown) continue;
    for (int a = 0; a < 3; ++a) z[3 * u + a] += s * e[3 * agg + a];
  }
}

// c += s·(A·P₀)ᵀ·z.
void restrict_through_a(const PreconditionerState& state, uint32_t nu, const double* z,
                        Eigen::VectorXd& c, double s) {
  for (uint32_t u = 0; u < nu; ++u) {
    const double z0 = s * z[3 * u], z1 = s * z[3 * u + 1], z2 = s * z[3 * u + 2];
    for (uint32_t t = state.ap_begin[u]; t < state.ap_begin[u + 1]; ++t) {
      const Sym3& k = state.ap_block[t];
      double* cj = c.data() + 3 * size_t(state.ap_aggregate[t]);
      cj[0] += k[0] * z0 + k[1] * z1 + k[2] * z2;
      cj[1] += k[1] * z0 + k[3] * z1 + k[4] * z2;
      cj[2] += k[2] * z0 + k[4] * z1 + k[5] * z2;
    }
  }
}

// t −= (A·P₀)·e over rows [begin, end).
void subtract_through_a(const PreconditionerState& state, uint32_t begin, uint32_t end,
                        const Eigen::VectorXd& e, double* t) {
  for (uint32_t u = begin; u < end; ++u) {
    double s0 = 0.0, s1 = 0.0, s2 = 0.0;
    for (uint32_t b = state.ap_begin[u]; b < state.ap_begin[u + 1]; ++b) {
      const Sym3& k = state.ap_block[b];
      const double* ej = e.data() + 3 * size_t(state.ap_aggregate[b]);
      s0 += k[0] * ej[0] + k[1] * ej[1] + k[2] * ej[2];
      s1 += k[1] * ej[0] + k[3] * ej[1] + k[4] * ej[2];
      s2 += k[2] * ej[0] + k[4] * ej[1] + k[5] * ej[2];
    }
    t[3 * u] -= s0, t[3 * u + 1] -= s1, t[3 * u + 2] -= s2;
  }
}

}  // namespace

void update_deflation(ImplicitCache& cache) {
  PreconditionerState& state = *cache.preconditioner;
  const uint32_t nu = cache.pattern.rows();
  state.residual.resize(3 * Eigen::Index(nu));
  const bool same_topology = state.built_for_topology == cache.topology_changes;
  const size_t moved = same_topology ? map_built_rows(cache, state) : ~size_t(0);
  if (same_topology && double(moved) <= cache.settings.two_level_rebuild_fraction * double(nu) &&
      refresh_coarse_operator(cache, state)) {
    state.coarse_valid = true;
    return;
  }
  build_aggregates(cache, state);
  map_built_rows(cache, state);
  state.coarse_valid = refresh_coarse_operator(cache, state);
  if (state.coarse_valid) group_factor_columns(state);
  ++cache.stats.preconditioner_builds;
}

void apply_deflation(const ImplicitCache& cache, const double* r, double* z) {
  const PreconditionerState& state = *cache.preconditioner;
  const uint32_t nu = cache.pattern.rows();
  const ImplicitSettings& settings = cache.settings;
  if (!state.coarse_valid) {  // E did not factorise (not seen): block-Jacobi, still SPD
    apply_block_inverse(state.inverse_block, r, z, 1.0, false, settings);
    return;
  }
  if (state.kind == Preconditioner::Deflation) {
    // z = S·r − Q·A·S·r; S·r and its restriction (A·P₀)ᵀ·S·r in one pass over the unknowns.
    state.coarse_rhs.setZero();
    for (uint32_t u = 0; u < nu; ++u) {
      const Sym3& k = state.inverse_block[u];
      const double r0 = r[3 * u], r1 = r[3 * u + 1], r2 = r[3 * u + 2];
      const double z0 = k[0] * r0 + k[1] * r1 + k[2] * r2;
      const double z1 = k[1] * r0 + k[3] * r1 + k[4] * r2;
      const double z2 = k[2] * r0 + k[4] * r1 + k[5] * r2;
      z[3 * u] = z0, z[3 * u + 1] = z1, z[3 * u + 2] = z2;
      for (uint32_t t = state.ap_begin[u]; t < state.ap_begin[u + 1]; ++t) {
        const Sym3& a = state.ap_block[t];
        double* cj = state.coarse_rhs.data() + 3 * size_t(state.ap_aggregate[t]);
        cj[0] += a[0] * z0 + a[1] * z1 + a[2] * z2;
        cj[1] += a[1] * z0 + a[3] * z1 + a[4] * z2;
        cj[2] += a[2] * z0 + a[4] * z1 + a[5] * z2;
      }
    }
    coarse_solve(state);
    prolong_constant(state, nu, state.coarse_solution, z, -1.0);
    return;
  }
  // Balancing: e₁ = E⁻¹·P₀ᵀ·r; z = S·(r − A·P₀·e₁); e₂ = E⁻¹·P₀ᵀ·(r − A·z); z += P₀·e₂.
  Eigen::VectorXd& t = state.residual;
  const Eigen::Index size = 3 * Eigen::Index(nu);
  restrict_constant(state, nu, r, state.coarse_rhs);
  coarse_solve(state);
  Eigen::Map<Eigen::VectorXd>(t.data(), size) = Eigen::Map<const Eigen::VectorXd>(r, size);
  subtract_through_a(state, 0, nu, state.coarse_solution, t.data());
  apply_block_inverse(state.inverse_block, t.data(), z, 1.0, false, settings);
  restrict_through_a(state, nu, z, state.coarse_rhs, -1.0);
  coarse_solve(state);
  prolong_constant(state, nu, state.coarse_solution, z, 1.0);
}

double deflation_coarse_step(const ImplicitCache& cache, const double* t, const double* r) {
  const PreconditionerState& state = *cache.preconditioner;
  if (!state.coarse_valid) return 0.0;
  const uint32_t nu = cache.pattern.rows();
  restrict_constant(state, nu, t, state.coarse_rhs);
  coarse_solve(state);
  if (!r) return 0.0;
  Eigen::VectorXd& c = state.coarse_work;  // coarse_solve is done with it
  restrict_constant(state, nu, r, c);
  return c.dot(state.coarse_solution);
}

void add_coarse_correction(const PreconditionerState& state, uint32_t begin, uint32_t end,
                           double y_sign, double* y, double* ay) {
  if (!state.coarse_valid) return;
  subtract_through_a(state, begin, end, state.coarse_solution, ay);
  const double* e = state.coarse_solution.data();
  for (uint32_t u = begin; u < end; ++u) {
    const uint32_t agg = state.aggregate_of_unknown[u];
    if (agg == kNotUnknown) continue;
    for (int a = 0; a < 3; ++a) y[3 * u + a] += y_sign * e[3 * agg + a];
  }
}

void deflate_guess(ImplicitCache& cache) {
  const PreconditionerState& state = *cache.preconditioner;
  if (!state.coarse_valid) return;
  StepSystem& sys = cache.system;
  const uint32_t nu = cache.pattern.rows();
  Eigen::VectorXd& r = state.residual;
  r = sys.rhs;
  add_block_product(cache.pattern, sys.block, sys.guess.data(), r.data(), -1.0, cache.settings);
  restrict_constant(state, nu, r.data(), state.coarse_rhs);
  coarse_solve(state);
  prolong_constant(state, nu, state.coarse_solution, sys.guess.data(), 1.0);
}

}  // namespace phaco::deform::implicit_detail
