#pragma once
// Implicit integrators of a membrane: backward Euler solved by conjugate gradients, and seed
// 004's approximate implicit predictor. Both stay stable at the frame step (1/120 s) with the
// capsule's real material, where an explicit step would need dt of a few microseconds.
//
// Implicit Euler (Baraff & Witkin 1998, one Newton step of backward Euler):
//
//   (M − dt·∂f/∂v − dt²·∂f/∂x)·Δv = dt·(f(x, v) + dt·∂f/∂x·v),   v⁺ = v + Δv,  x⁺ = x + dt·v⁺
//
// f: springs (linear or quadratic law), gravity m·g, damping and viscosity −m·(γ + κ)·v, glue
// −g·(x − x_glue). ∂f/∂x from 3×3 spring blocks (spring_force_jacobian below); ∂f/∂v = −m·(γ+κ)·I.
// Unknowns are the free particles of the active set (all free particles when the set is empty);
// anchored, scripted and sleeping particles are fixed during the step (a scripted particle was
// already put at its end-of-frame position by the tool, DESIGN.md §4 step 1), so they bring no
// velocity term into the right side. Cost follows the active set: only its springs and unknowns are
// touched (plus O(active) bookkeeping).
//
// One linearised step is not enough on its own at the capsule's k·dt²/m ≈ 10⁷: it is then a full
// Newton step of the static problem, and where springs rotate or buckle it overshoots and pumps
// energy in (measured: level 1 blew up after 16 frames). So the step is a Newton step on the
// incremental potential of backward Euler (Gast et al. 2015),
//   Φ(x) = Σ m/(2dt²)·|x − x_n − dt·v_n|² + Σ m·(γ+κ)/(2dt)·|x − x_n|² + U_springs(x)
//          + Σ g/2·|x − x_glue|² − Σ m·g·x,
// whose minimiser is the backward-Euler state and whose Newton direction from x_n is exactly
// Δx = dt·(v_n + Δv) above; the step x⁺ = x_n + α·Δx, v⁺ = α·Δx/dt takes the largest α in
// {1, ½, ¼, ...} with Φ(x⁺) ≤ Φ(x_n). With α = 1 (the usual case) it is Baraff–Witkin's step.
//
// The system is solved by preconditioned CG, relative tolerance settings.cg_tolerance
// (‖r‖ ≤ tol·‖b‖), warm-started from the previous step's Δv of each particle, preconditioned by
// settings.preconditioner (implicit_solver.hpp): Jacobi, 3×3 block-Jacobi, incomplete Cholesky
// of the assembled matrix, a two-level smoothed-aggregation cycle (Tamstorf, Jones & McCormick
// 2015), or deflation / balancing on unsmoothed aggregates (Tang et al. 2009).
// Incomplete Cholesky is refactored when the unknown set or the topology changes, the
// two-level hierarchy after a topology change or a large change of the set; otherwise both are
// reused stale (still SPD, so CG stays valid; only its speed depends on staleness).
// Two operators: an assembled row-major sparse matrix whose pattern is built once per unknown set
// and whose values are refilled every step, or a matrix-free product over the stored 3×3 blocks of
// the block-CSR rows (the default: ~2× fewer bytes per product; in its earlier scatter-over-springs
// form it measured 2.2–3.4× faster per step at levels 0–5, docs/implicit_and_active.md). The
// matrix-free product gathers each row in a fixed order, so rows split over threads with the same
// bits on any thread count.
// Threads: Jacobi, block-Jacobi and deflation with the matrix-free operator run the step's
// assembly and a row-chunked CG on a team of two threads (implicit_team_cg.cpp,
// engine/schedule/phased_team.hpp), formed before the assembly so that its worker is awake when
// the CG starts (deflation's small coarse solve runs on one thread between two phases); the other
// preconditioners and the assembled operator use Eigen's ConjugateGradient, whose product runs on
// several threads above settings.parallel_min_unknowns.
// Every sum has a fixed order, so 1 and 2 threads give the same bits. Eigen's CG allocates its
// four work vectors per solve, the factored preconditioners when they are rebuilt; the
// row-chunked CG keeps its work vectors in the cache (CgWork) and reuses them.
//
// Approximate implicit predictor (seed 004 "pre computes the solution to a linear system [9]",
// [9] = Desbrun, Schröder & Barr 1999): the system matrix is frozen and factorised once
// (SimplicialLDLT), A = M·(1 + dt·(γ+κ)) + dt²·(H + g·I), and every step filters the exact
// nonlinear force through it:
//
//   Δv = A⁻¹·dt·(f(x, v) − dt·(H + g·I)·v),   then the same line search as implicit Euler
//
// which is Desbrun's v⁺ = v + W·dt·M⁻¹·f, W = (I + dt²·M⁻¹·H)⁻¹, plus backward Euler's velocity
// term. Two frozen stiffnesses H (settings.predictor_stiffness):
//   Isotropic       Desbrun's choice: k_e·I per spring, the same for x, y and z, so one scalar n×n
//                   factorisation serves all three axes. It dominates the true stiffness
//                   (k·I ≥ k·d̂d̂ᵀ + k·(1 − l0/l)·(I − d̂d̂ᵀ) while l < 2·l0), hence stable, but a
//                   membrane's out-of-plane stiffness comes only from its tension (≈ prestretch·k),
//                   so the filter slows out-of-plane motion by about 1/prestretch.
//   FrozenJacobian  the spring blocks of implicit Euler at the configuration of the
//                   precomputation (3n×3n): for small displacements it is implicit Euler.
// The factorisation is recomputed when dt, masses, particle kinds (a grasp turns a free particle
// into a scripted one), damping, glue, the law or the spring count change, and on invalidate()
// (call it after a cut or a tear, or to re-freeze H at the current shape). Desbrun's rotational
// post-correction is not applied: our membranes are held at their rim, so there is no free rigid
// rotation for the frozen filter to damp. The predictor's unknowns are all free particles (the
// factorisation is per body); with an active set only the set's particles are moved.
//
// Reads: particles (x, v, inv_mass, kind), springs, dynamics, glue, active set.
// Writes: particles (x, v of the unknowns), forces (of the unknowns: the force at the start of the
// step), cache.
#include <Eigen/Core>
#include <Eigen/SparseCholesky>
#include <Eigen/SparseCore>
#include <array>
#include <cstdint>
#include <memory>
#include <optional>
#include <span>
#include <string_view>
#include <vector>

#include "engine/schedule/alone_arena.hpp"
#include "systems/deform/membrane.hpp"
#include "systems/deform/team_choice.hpp"

namespace phaco::deform {

enum class CgOperator : uint8_t { Assembled, MatrixFree };
enum class PredictorStiffness : uint8_t { Isotropic, FrozenJacobian };
// CG preconditioners of implicit Euler (implicit_solver.hpp, docs/implicit_and_active.md).
enum class Preconditioner : uint8_t {
  Jacobi,
  BlockJacobi,
  IncompleteCholesky,
  TwoLevel,
  Deflation,
  Balancing
};

enum class TeamPolicy { Timed, Always };

struct ImplicitSettings {
  double cg_tolerance = 1.0e-6;  // relative residual
  int cg_max_iterations = 1000;
  bool warm_start = true;
  CgOperator cg_operator =
      CgOperator::MatrixFree;  // measured 3× faster (docs/implicit_and_active.md)
  // Deflation: block-Jacobi with a coarse space of node aggregates projected out, a third of
  // block-Jacobi's CG iterations on the capsule (33.5 against 95.6 per stepped frame at level 3)
  // at about its time; on the team where the team measured cheaper (team_policy).
  Preconditioner preconditioner = Preconditioner::Deflation;
  // The matrix-free product and the block preconditioners split their rows over threads from this
  // many unknowns on (chunks of parallel_grain_unknowns rows); below it they run serially, so a
  // small active set pays no threading overhead. Measured (docs/implicit_and_active.md).
  uint32_t parallel_min_unknowns = 1024;
  uint32_t parallel_grain_unknowns = 512;
  // Jacobi and block-Jacobi CG (implicit_team_cg.cpp) works in chunks of this many rows, fixed by
  // the row count alone so that its sums, hence its bits, do not depend on the threads; a team of
  // threads works the iterations from this many rows on (below it, the calling thread alone).
  uint32_t cg_chunk_rows = 128;
  // Assembly splits its springs and its rows over threads in chunks of these (results do not
  // depend on the split).
  uint32_t parallel_grain_springs = 512;
  uint32_t parallel_grain_rows = 128;
  uint32_t cg_team_min_rows = 256;
  // From cg_team_min_rows nodes on, Timed runs a step on the team or on the calling thread alone,
  // whichever measured cheaper for sets of its size (team_choice.hpp); Always forms the team
  // (tests that split every loop). The bits are the same either way.
  TeamPolicy team_policy = TeamPolicy::Timed;
  // TwoLevel: rebuild the hierarchy when more than this fraction of the unknowns entered or left
  // the set since its build (otherwise reuse it stale); a topology change always rebuilds.
  double two_level_rebuild_fraction = 0.2;
  // Backtracking on the incremental potential: halve the Newton step at most this many times.
  int max_line_search_halvings = 12;
  PredictorStiffness predictor_stiffness = PredictorStiffness::FrozenJacobian;
  // Quadratic springs have no stiffness at rest; the predictor freezes them at the extension
  // max(|l − l0|, this) (the default equals SpringMaterial::quadratic_reference_mm).
  double predictor_quadratic_extension_mm = 0.01;
};

std::string_view to_string(Preconditioner p);
std::optional<Preconditioner> parse_preconditioner(std::string_view s);

struct ImplicitStats {
  uint64_t steps = 0;             // implicit Euler steps
  int cg_iterations = 0;          // last step
  double cg_residual = 0.0;       // last step, ‖r‖/‖b‖
  bool cg_converged = true;       // last step reached the tolerance
  double step_fraction = 1.0;     // last step: line-search fraction α of the Newton step taken
  uint64_t line_search_cuts = 0;  // steps that took α < 1
  uint64_t cg_iterations_total = 0;
  uint64_t team_steps = 0;      // steps whose assembly and solve ran on the team of two
  uint32_t unknowns = 0;        // particles solved for, last step
  uint32_t springs = 0;         // springs assembled, last step
  uint64_t nonzeros = 0;        // scalar entries of the operator (stored or applied), last step
  uint64_t pattern_builds = 0;  // implicit Euler: unknown set or springs changed
  uint64_t preconditioner_builds = 0;  // incomplete Cholesky / two-level factorisations
  uint64_t predictor_steps = 0;
  uint64_t precomputations = 0;  // predictor factorisations
  uint32_t predictor_unknowns = 0;
};

// Symmetric 3×3 block as (xx, xy, xz, yy, yz, zz).
using Sym3 = std::array<double, 6>;

struct SpringForceJacobian {
  std::array<double, 3> force_on_i{};  // mN; force on j is the opposite
  Sym3 k{};                            // mN/mm; ∂f_i/∂x_j = k, ∂f_i/∂x_i = −k
};

// One spring from i to j (d = x_j − x_i): force on i and its Jacobian block. Linear F = k·(l − l0),
// quadratic F = k·(l − l0)·|l − l0|; block = F'(l)·d̂d̂ᵀ + max(F/l, 0)·(I − d̂d̂ᵀ). The transverse
// term F/l is negative under compression; it is clamped to zero so the block, and with it the
// system matrix, stays positive semidefinite (the buckling direction gets no negative stiffness).
SpringForceJacobian spring_force_jacobian(double dx, double dy, double dz, double rest_length,
                                          double stiffness, SpringLaw law);

constexpr uint32_t kNotUnknown = 0xffffffffu;

// --- implicit Euler's cache, by part ---

// Which particles the step solves for. Per-particle arrays grow with the particle table (a cut
// appends particles) and keep their contents.
struct UnknownSet {
  std::vector<uint32_t> unknown_of;  // per particle: unknown index, or kNotUnknown
  std::vector<uint32_t> particles;   // particle of each unknown, sorted
  std::vector<uint32_t> springs;     // springs with an unknown end, sorted
  std::vector<uint32_t> candidate_particles, candidate_springs;  // scratch of the next selection
};

// Block-CSR sparsity of the system over the unknowns (row u: u itself and the unknowns joined to
// it by a step spring, sorted). Built once per unknown set; indices into UnknownSet::springs.
struct BlockPattern {
  bool valid = false;
  CgOperator built_for =
      CgOperator::MatrixFree;       // the assembled operator also needs `matrix`'s pattern
  std::vector<uint32_t> row_begin;  // per unknown + 1: first block of the row
  std::vector<uint32_t> col;        // per block: column unknown
  std::vector<uint32_t> diag_pos;   // per unknown: block of the diagonal
  std::vector<uint32_t> spring_ui,
      spring_uj;  // per step spring: unknown of each end, or kNotUnknown
  std::vector<uint32_t> spring_pos_ij,
      spring_pos_ji;  // per step spring: block of j in i's row and back
  // Per unknown + 1 / per entry: the step springs at the unknown, in increasing order, as
  // t·2 + (1 if the unknown is the spring's j end): assembly gathers each row from them.
  std::vector<uint32_t> row_spring_begin, row_spring;
  uint32_t rows() const {
    return row_begin.empty() ? 0u : static_cast<uint32_t>(row_begin.size() - 1);
  }
};

// This step's system A·Δv = b (A = M(1 + dt(γ+κ)) + dt²(K + g·I), b = dt·(f + dt·K·v), see top).
struct StepSystem {
  std::vector<Sym3> spring_k;                       // per step spring: ∂f_i/∂x_j, mN/mm
  std::vector<std::array<double, 3>> spring_force;  // per step spring: its force on i, mN
  std::vector<std::array<double, 3>>
      spring_kw;  // per step spring: k·(v_j − v_i), unknown ends only
  std::vector<std::pair<uint32_t, uint32_t>> loads;  // (unknown, index in Membrane::loads), sorted
  std::vector<Sym3> block;  // per block of the pattern: A's 3×3 block, kg (mN·s²/mm)
  Eigen::SparseMatrix<double, Eigen::RowMajor, int>
      matrix;                 // assembled A (Assembled operator, factorisations)
  Eigen::VectorXd force;      // 3 per unknown: f at the start of the step, mN
  Eigen::VectorXd rhs;        // 3 per unknown: b, mN·s
  Eigen::VectorXd guess, dv;  // 3 per unknown: CG's first guess and answer Δv, mm/s
  Eigen::VectorXd step_dx;    // 3 per unknown: Newton step Δx = dt·(v + Δv), mm
};

// Work vectors of the row-chunked CG (implicit_team_cg.cpp), kept between steps: a steady-state
// solve allocates nothing.
struct CgWork {
  std::vector<double> residual, preconditioned, direction, product;  // r, z, p, A·p: 3 per unknown
  // Per chunk: partial sums, reduced in chunk order. rz is double-buffered by iteration parity:
  // iteration i reads r·z of the one before while writing its own.
  std::vector<double> rhs_norm2, residual_norm2, direction_product, rz[2];
};

// Factorised preconditioner state (implicit_solver.hpp); opaque here to keep Eigen's sparse
// factorisations out of every includer.
struct PreconditionerState;
struct PreconditionerStateDeleter {
  void operator()(PreconditionerState* p) const;
};

// Scratch and state carried between steps of one body. Sized on first use (and when the particle
// count or the unknown set changes); steady-state steps reuse it.
struct ImplicitCache {
  ImplicitSettings settings;
  ImplicitStats stats;

  // Call after a cut or tear (topology), or a material change: rebuilds pattern and factorisation.
  void invalidate() { pattern.valid = false, predictor_valid = false, ++topology_changes; }
  uint64_t topology_changes = 0;  // invalidate() calls

  // --- implicit Euler ---
  UnknownSet unknowns;
  BlockPattern pattern;
  StepSystem system;
  CgWork cg;
  std::vector<double> warm_dv;  // 3 per particle: the last Δv (mm/s), CG's first guess
  std::unique_ptr<PreconditionerState, PreconditionerStateDeleter> preconditioner;
  TeamChoice team_choice;  // runtime only: which way recent steps of each size cost less
  AloneArena alone;        // runtime only: where a step not on the team runs its loops

  // --- predictor ---
  bool predictor_valid = false;
  uint64_t predictor_key = 0;                  // hash of what the factorisation depends on
  std::vector<uint32_t> predictor_unknown_of;  // per particle
  std::vector<uint32_t> predictor_unknowns;
  std::vector<uint32_t> predictor_springs;  // springs with an unknown end
  std::vector<Sym3> predictor_k;  // per predictor spring: frozen block (k·I when isotropic)
  // Behind a pointer so the cache (and every body's state holding it) stays movable: Eigen's
  // factorisations are neither copyable nor movable.
  std::unique_ptr<Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>>> predictor_factor =
      std::make_unique<Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>>>();
  Eigen::VectorXd predictor_force, predictor_rhs, predictor_dv, predictor_dx;  // 3 per unknown
};

namespace implicit_detail {
// Mass scaling as the other deform integrators read it: a non-positive scale counts as 1.
inline double mass_scale(const Dynamics& d) {
  return d.mass_scale > 0.0f ? double(d.mass_scale) : 1.0;
}

// The largest α in {1, ½, ¼, ...} (at most settings.max_line_search_halvings cuts) with
// Φ(x_n + α·Δx) ≤ Φ(x_n), Φ the incremental potential above. unknown_of maps a particle to its
// unknown u (Δx at step_dx[3u..3u+2]) or kNotUnknown; `springs` are those with an unknown end.
double line_search(const Membrane& m, double dt, int max_halvings,
                   std::span<const uint32_t> unknowns, std::span<const uint32_t> unknown_of,
                   std::span<const uint32_t> springs, const double* step_dx);
// Adds the membrane's point loads on unknowns to a force vector laid out 3 per unknown (mN).
void add_point_loads(const Membrane& m, std::span<const uint32_t> unknown_of, double* force);
}  // namespace implicit_detail

// One backward-Euler step of the membrane (see the top of this file).
void implicit_euler_step(Membrane& m, double dt_s, ImplicitCache& cache);

// One step of the seed-004 approximate implicit predictor (see the top of this file).
void implicit_predictor_step(Membrane& m, double dt_s, ImplicitCache& cache);

}  // namespace phaco::deform
