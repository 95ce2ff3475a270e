#pragma once
// Measurements of shape matching (systems/shape_match, seed 002 §6.2) for the `phaco-perf lens`
// study: Horn (float/double, Eigen/quartic solver) against MHTG05 polar decomposition (with and
// without the determinant check) on degenerate fragments, the float-vs-double error on nearly
// collinear clusters, the cost per fragment size, and the whole-lens pass. Plain rows; no printing,
// no files.
#include <cstdint>
#include <string>
#include <vector>

namespace phaco::perf {

// (a) One case × one method over `trials` random rigid transforms.
struct ShapeDegenerateRow {
  std::string case_name;  // one_cell, two_cells, three_collinear, nearly_collinear_1e-4, coplanar,
                          // noisy, reflected
  std::string method;     // horn_eigen_float, horn_eigen_double, horn_quartic_float,
                       // horn_quartic_double, polar_det, polar_no_det, policy, policy_float_first
  int trials = 0;
  double max_angle_deg =
      0;  // vs the true rotation (for reflections: angle of Rtrueᵀ R's rotation part)
  double mean_angle_deg = 0;
  double min_det = 0;      // det of the returned matrix, smallest over trials
  double max_goal_mm = 0;  // max |R(a − â) + b̂ − b| over cells and trials
  int flagged = 0;  // trials flagged ill-conditioned (Horn) / not solved as determined (policy)
};
std::vector<ShapeDegenerateRow> measure_shape_degenerate(int trials = 200, uint64_t seed = 1);

// Float against double on nearly collinear clusters: cells `offset_mm` off a 4 mm line.
struct ShapePrecisionRow {
  double offset_mm = 0;
  int cells = 0;
  std::string method;  // horn_{eigen,quartic}_{float,double}, policy, policy_float_first
  int trials = 0;
  double max_angle_deg = 0;
  double median_gap = 0;  // relative eigen-gap (λ1 − λ2)/λ1 in double
};
std::vector<ShapePrecisionRow> measure_shape_precision(int trials = 200, uint64_t seed = 2);

// (b) Cost of one fragment: moments + solve, and the solve alone from moments.
struct ShapeTimingRow {
  std::string method;  // as in ShapeDegenerateRow, plus policy
  int cells = 0;
  double ns_per_fragment = 0;  // moments + solve (+ nothing else)
  double ns_solve = 0;         // from precomputed moments
};
std::vector<ShapeTimingRow> measure_shape_timing(double min_seconds = 0.05);

// (c) One match_lens pass over the level's lens (tet centres as cells, tet volumes as masses),
// split into `fragments` spatially compact fragments, each moved rigidly plus noise.
struct ShapeLensRow {
  int level = 0;
  uint32_t cells = 0;
  uint32_t fragments = 0;
  int threads = 0;
  double ms = 0;  // best mean ms per pass
  double ns_per_cell = 0;
  uint32_t fast = 0, exact = 0, continuous = 0, kept = 0;  // LensPassStats paths
};
std::vector<ShapeLensRow> measure_shape_lens(int level = 3,
                                             std::vector<uint32_t> fragment_counts = {1, 100, 5000},
                                             std::vector<int> threads = {1, 2},
                                             double min_seconds = 0.2);

}  // namespace phaco::perf
