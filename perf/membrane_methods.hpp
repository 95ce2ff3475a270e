#pragma once
// The membrane study's measurements, one function per question; study_membrane.cpp sweeps them
// and writes the tables, charts and section.
//
//   cost        time per step of each method on the level's capsule, 1 or 2 threads
//   active      a grasp at the centre with the 5-hop active node set and the wake rules (force
//               threshold above the unloaded mesh's residual imbalance): step cost vs mesh size
//   accuracy    the load case (flat capsule, pre-stretched, point load at the centre, viscosity
//               critical for the fundamental mode): state after one frame (1/120 s) against the
//               static equilibrium, and the wall time that frame cost
//   stability   largest stable step of each deform integrator against k/m (deform::stability_map)
#include <cstdint>
#include <string>
#include <vector>

#include "perf/membrane_fixture.hpp"

namespace phaco::perf {

struct CostSample {
  std::string method;
  double seconds_per_step = 0;
  double dt_s = 0;  // the step the method was timed at
  std::string note;
};

// Methods timed per level: "spring pass", "node pass", "plain step" (ours), then every deform
// integrator available, then "btSoftBody" (1 thread only; Bullet's solver is serial).
std::vector<CostSample> measure_costs(MembraneFixture& m, int threads, double min_seconds,
                                      bool with_bullet);

struct ActiveSample {
  uint32_t active_particles = 0, active_springs = 0;
  double seconds_per_step = 0;  // set update + restricted spring pass + restricted node pass
};

ActiveSample measure_active_grasp(MembraneFixture& m, int threads, double min_seconds);

struct AccuracySample {
  std::string method;
  std::string setting;  // "mass ×100", "dt 1/480 s", "16 layers × 4 sweeps", "10 iterations"
  double wall_s_per_frame = 0;  // wall time for one 1/120 s frame
  double cost_per_sim_s = 0;    // wall seconds per simulated second = 120 × wall_s_per_frame
  double error = 0;  // ‖u − u_ref‖ / ‖u_ref‖ over free particles (u: displacement under the load)
  bool stable = true;
};

struct LoadCase {
  double load_mn = 0;          // downward point force at the centre
  double viscosity_per_s = 0;  // critical for the fundamental mode
  double frame_s = 1.0 / 120;
  double reference_centre_deflection_mm = 0;
  double tension_mn_mm = 0;  // 1.5·E·h·p/(1 − p), equilateral-lattice estimate
};

// Builds the flat fixture at `level`, relaxes it in-plane to its static equilibrium, solves the
// loaded static reference (procedures/reference) and runs every method's settings for one frame.
std::vector<AccuracySample> measure_accuracy(int level, bool quick, LoadCase* load_case);

struct StabilitySample {
  std::string method;
  double k_over_m = 0;               // 1/s², max over particles of Σk/m
  double dt_max_s = 0;               // largest stable step (deform::largest_stable_dt)
  double dt_theory_s = 0;            // 2/√(k/m)-type bound where one is known (0 otherwise)
  bool stable_everywhere = false;    // dt_max_s is the probe's upper bound
  bool unstable_everywhere = false;  // dt_max_s is 0
};

std::vector<StabilitySample> measure_stability(bool quick);

}  // namespace phaco::perf
