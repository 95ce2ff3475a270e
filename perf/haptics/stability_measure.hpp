#pragma once
// Measurements of the local haptic force model (systems/haptic_model) for the `phaco-perf haptics`
// study (issue 6, "Stability" and "Continuity"): rows only, no printing.
//
//   (a) stiffness limit against rate: a simulated device (mass m, physical damping b, force held
//       between samples) pushed into a virtual wall, or holding a grasped membrane pulled and
//       released; the largest stiffness whose oscillation energy does not grow, by bisection,
//       next to Colgate & Schenkel's bound K = 2·b/T (b > K·T/2, no virtual damper);
//   (b) continuity: the largest tick-to-tick force jump as a fraction of the force's range, with
//       models arriving at 120 Hz, at 30 Hz, and at 30 Hz with a 200 ms stall, crossfade on/off;
//   (c) tick cost: ns per haptic_tick (contact on a membrane patch) against the local node count,
//       mean, p99 and max over many ticks, and the cost of adopting a model.
#include <cstdint>
#include <string>
#include <vector>

namespace phaco::perf {

struct StiffnessLimitRow {
  std::string scene;  // "wall" or "grasped membrane"
  double rate_hz = 0;
  double device_mass_kg = 0;
  double device_damping_mn_s_per_mm = 0;  // b
  double passive_limit_mn_per_mm = 0;     // largest K whose energy did not grow (bisection)
  double colgate_bound_mn_per_mm = 0;     // 2·b/T
};
// Rates default to 250, 500, 1000, 2000, 4000 Hz.
std::vector<StiffnessLimitRow> measure_stiffness_limits(std::vector<double> rates_hz = {});

struct ContinuityRow {
  std::string models;  // "120 Hz", "30 Hz", "30 Hz + 200 ms stall"
  bool crossfade = false;
  double range_mn = 0;       // max − min of the force's z over the run
  double max_jump_mn = 0;    // largest |F_k − F_k−1|
  double jump_fraction = 0;  // max_jump / range
};
std::vector<ContinuityRow> measure_continuity();

struct TickCostRow {
  uint32_t nodes = 0, springs = 0, triangles = 0;
  uint64_t ticks = 0;
  double mean_ns = 0, p99_ns = 0, max_ns = 0;
  double mean_cg_iterations = 0;
  double adopt_mean_ns = 0;  // adopt_model (copy of the model, sides)
  double blend_mean_ns = 0;  // a tick while two models are ticked (crossfade)
};
// Node counts default to 0 (wall), 64, 121, 256, 384.
std::vector<TickCostRow> measure_tick_cost(std::vector<uint32_t> node_counts = {},
                                           uint64_t ticks = 20000);

}  // namespace phaco::perf
