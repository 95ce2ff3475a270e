#pragma once
// The membrane every perf study and micro-benchmark runs: the anterior capsule of the standard eye
// at a resolution level (eye::make_capsule, curvilinear layout), its rim pinned (anchored, mass 0:
// the zonules hold it), lumped mass ρ·h·A/3 per triangle corner, one spring per edge from
// springs::build_springs. Optionally flattened to z = 0 (the analytic membrane's disc).
//
// Also the "plain SoA explicit step" the targets were measured with: one float pass over
// the springs (springs::add_spring_forces, parallel by blocks) and one over the nodes (symplectic
// Euler with linear damping, which also clears the force accumulator for the next step).
#include <cstdint>
#include <vector>

#include "components/particles.hpp"
#include "components/springs.hpp"
#include "components/triangles.hpp"

namespace phaco::perf {

struct FixtureOptions {
  int level = 3;
  bool flat = false;                 // project the capsule onto z = 0
  double youngs_modulus_kpa = 2000;  // capsule, DESIGN.md §6
  double thickness_mm = 0.013;
  double density_kg_m3 = 1000;
  double prestretch = 0.02;  // rest length = (1 − p)·mesh length
  SpringLaw law = SpringLaw::Linear;
  StiffnessWeighting weighting = StiffnessWeighting::AreaWeighted;
};

struct MembraneFixture {
  FixtureOptions options;
  Particles particles;
  Triangles triangles;
  Springs springs;
  SpringBlocks blocks;
  Forces forces;              // zeroed
  std::vector<uint32_t> rim;  // anchored particles, increasing
  uint32_t centre = 0;        // the vertex on the optical axis (the loaded one)
  double radius_mm = 0;       // projected rim radius
  double mean_edge_mm = 0;
  double total_mass_kg = 0;
  double max_k_over_m = 0;  // 1/s², from springs::max_stiffness_over_mass

  uint32_t vertex_count() const { return particles.slots.size(); }
  uint32_t spring_count() const { return springs.slots.size(); }
  // Largest stable symplectic-Euler step, 2/ω_max with ω_max² ≤ max Σk/m (Gershgorin), times
  // `safety`.
  double stable_dt(double safety = 0.9) const;
};

MembraneFixture make_membrane_fixture(const FixtureOptions& options);

// Bytes of the hot per-step columns: particles (x, y, z, vx, vy, vz, inv_mass, kind) + forces
// (fx, fy, fz) per vertex; springs (i, j, rest_length, stiffness) per spring.
double hot_bytes_per_vertex();
double hot_bytes_per_spring();
// Bytes one plain step must move at least once (reads + writes of every hot column it touches).
double plain_step_bytes(uint32_t vertices, uint32_t springs);
double spring_pass_bytes(uint32_t vertices, uint32_t springs);

// The node pass of the plain step, parallel over particles in fixed chunks:
//   v += dt·(f·inv_mass − damping·v); x += dt·v; f = 0.
// Anchored particles (inv_mass 0, zero velocity) stay where they are.
void integrate_nodes(Particles& particles, Forces& forces, float dt, float damping_per_s);

// One plain SoA explicit step: external point force on `load_node` (if load != 0), spring pass,
// node pass. Bit-identical for any thread count.
void plain_step(MembraneFixture& m, float dt, float damping_per_s, uint32_t load_node,
                float load_z_mn);

}  // namespace phaco::perf
