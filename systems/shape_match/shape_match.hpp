#pragma once
// Quasi-static shape-matching correction of the lens fragments (seed 002 §6.2, after MHTG05):
// per fragment, the optimal rigid map rest → current by Horn's closed form (horn.hpp), goal
// positions g_i = R(a_i − â) + b̂, and the pull x_i += α (g_i − x_i) with stiffness α ∈ [0, 1].
//
// Two things the seed leaves open, decided here:
//
// Precision (measured, docs/shape_matching.md). A fragment of three or more cells is first solved
// by the characteristic quartic in double: it is ~4× cheaper than Eigen's dense solver, and in
// scalar code double costs the same as float, while float's error is ε_float/gap (Eigen) or
// ε_float/gap² (quartic) — a nearly collinear cluster comes out up to 180° wrong in float. The
// result is kept unless it flags itself ill-conditioned (gap < kMinGapQuartic). Otherwise
// (one or two cells, collinear or nearly so) Eigen's dense solver in double decides. The float
// first attempt stays selectable (`first_precision`) for the measurements; fragments of at most
// `small_fragment` cells never use it.
//
// Continuity. When the double gap is below `degenerate_gap` (one cell, two cells, collinear cells)
// every unit vector of the top eigenspace span{e1, e2} is optimal: the twist about the line is
// free, and a solver returns an arbitrary one that can jump from frame to frame. We take the
// optimal rotation closest to the fragment's previous one: the previous quaternion projected onto
// span{e1, e2}, normalised. One cell (nothing determined) keeps the previous rotation. The goal
// positions are continuous either way (the twist only moves the cells' off-line components, which
// are below the threshold); the quaternion is kept continuous too because the rest of the frame
// (nucleus rotation, rendering) reads it.
//
// Reads: the lens cells' rest positions and masses, the fragments (CSR). Writes: the cells'
// current positions, each fragment's rotation (its previous one in, the new one out).
#include <cstdint>
#include <span>

#include "engine/core/math.hpp"
#include "systems/shape_match/horn.hpp"

namespace phaco::shape_match {

enum class Precision : uint8_t { Float, Double };

struct MatchSettings {
  double stiffness = 1.0;                 // α ∈ [0, 1]: share of the way to the goal per call
  Solver first_solver = Solver::Quartic;  // the cheap first attempt
  Precision first_precision = Precision::Double;
  uint32_t small_fragment = 4;              // at most this many cells: no float first attempt
  double degenerate_gap = kMinGap<double>;  // exact solve's gap below which the twist is free
};

// How a fragment was solved (for stats and tests).
enum class MatchPath : uint8_t {
  KeepPrevious,  // one cell or all cells at one point: rotation unchanged
  Fast,          // first attempt accepted
  Exact,         // Eigen's dense solver in double, determined
  Continuous,    // Eigen in double, top eigenspace two-dimensional: previous rotation projected
};

struct FragmentMatch {
  Quat rotation = Quat::Identity();      // unit, same hemisphere as the previous one
  Vec3 rest_centroid = Vec3::Zero();     // â, mm
  Vec3 current_centroid = Vec3::Zero();  // b̂, mm
  double gap = 0;                        // relative eigen-gap of the solve that decided
  MatchPath path = MatchPath::KeepPrevious;
};

// The optimal rotation from moments (accumulated in double), by the policy above.
FragmentMatch match_moments(const Moments<double>& m, const Quat& previous,
                            const MatchSettings& settings = {});

// Moments of the cells `ids` (all cells when empty), then match_moments.
template <class P>
FragmentMatch match_fragment(std::span<const Vec3T<P>> rest, std::span<const Vec3T<P>> current,
                             std::span<const P> masses, const Quat& previous,
                             const MatchSettings& settings = {},
                             std::span<const uint32_t> ids = {});

// Goal of a rest position a: g = R(a − â) + b̂.
inline Vec3 goal_position(const FragmentMatch& f, const Vec3& rest) {
  return f.rotation * (rest - f.rest_centroid) + f.current_centroid;
}

// x_i += α (g_i − x_i) for the cells `ids` (all when empty).
template <class P>
void pull_to_goals(const FragmentMatch& f, std::span<const Vec3T<P>> rest,
                   std::span<Vec3T<P>> current, double stiffness,
                   std::span<const uint32_t> ids = {});

// Fragments as CSR: fragment f owns cells[offsets[f] .. offsets[f + 1]).
struct FragmentList {
  std::span<const uint32_t> offsets;  // fragment count + 1 entries, offsets[0] = 0
  std::span<const uint32_t> cells;    // cell ids, grouped by fragment
  uint32_t count() const { return offsets.empty() ? 0 : static_cast<uint32_t>(offsets.size() - 1); }
};

struct LensPassStats {
  uint32_t fragments = 0;
  uint32_t cells = 0;
  uint32_t kept = 0;        // MatchPath::KeepPrevious
  uint32_t fast = 0;        // MatchPath::Fast
  uint32_t exact = 0;       // MatchPath::Exact
  uint32_t continuous = 0;  // MatchPath::Continuous
};

// One shape-matching pass over the whole lens: every fragment matched and pulled, fragments in
// parallel (parallel_for over fragments; a fragment larger than kParallelCells cells is itself
// reduced in parallel, in a fixed chunk order). `rotations` holds one quaternion per fragment,
// previous in, new out. Bit-identical for any thread count. Allocates nothing.
constexpr uint32_t kParallelCells = 16384;

template <class P>
LensPassStats match_lens(std::span<const Vec3T<P>> rest, std::span<Vec3T<P>> current,
                         std::span<const P> masses, FragmentList fragments,
                         std::span<Quat> rotations, const MatchSettings& settings = {});

}  // namespace phaco::shape_match
