#pragma once
// Fragment contact by SPH (seed 002 §6.1): pressure-like repulsion between boundary cells of
// DIFFERENT fragments, found on the neighbour grid of cell size 2h (grid.hpp).
//
// Force law. MCG03 (eq. 10) pushes particle i away from j with −m_j (p_i + p_j)/(2ρ_j) ∇W(r_ij).
// For contact we keep its shape and replace the pressure term by one contact constant, so the pair
// force is a function of the pair alone, equal and opposite by construction:
//
//   f_ij = max(0, k·h − c·v_n) · ĝ(r) · n̂,      n̂ = (x_i − x_j)/r,  v_n = (v_i − v_j)·n̂,
//   ĝ(r) = |∇W_poly6(max(r, h/√5), h)| / |∇W_poly6(h/√5, h)|   ∈ [0, 1],
//
// k the contact stiffness (mN/mm; the pair force peaks at k·h), c a damping along the normal
// (mN·s/mm; only ever adds repulsion to an approaching pair and never turns into attraction).
// ĝ is the seed's 6th-order kernel's gradient shape (kernel.hpp), 0 at r = h, rising to 1 at
// h/√5 ≈ 0.447h and held at 1 closer in (the raw poly6 gradient falls back to 0 at r = 0, which
// would let deep pairs pass through). Coincident pairs (r = 0) have no direction and exert nothing.
//
// Exactness. f_ij is computed as s(r², (v_i − v_j)·(x_i − x_j)) · (x_i − x_j): both arguments of s
// have the same bits for (i, j) and (j, i), and the vector only changes sign, so f_ji = −f_ij
// bit for bit. Each particle sums its own pairs in grid order (deterministic, any thread count);
// total momentum changes only by the rounding of those per-particle sums.
//
// Scope (DESIGN §3: model no more than the scene needs): with fewer than two fragments the call
// returns at once; otherwise only particles flagged boundary enter the grid, and only the grid
// cells whose 3×3×3 block of cells (edge 2h) holds two fragments or more are scanned (a particle
// elsewhere has no pair: skipping it adds nothing, so the forces are the same bits); within those,
// with sub-cells, a particle whose 27 sub-cells hold its own fragment only is skipped too (the same
// argument one level finer, decided once per cell and octant).
//
// Reads: positions, velocities, fragment labels, boundary flags. Writes: forces (added, mN).
#include <array>
#include <cstdint>
#include <span>
#include <vector>

#include "systems/sph/grid.hpp"

namespace phaco::sph {

struct ContactParams {
  float h = 0.15f;         // support, mm
  float stiffness = 1.0f;  // k, mN/mm
  float damping = 0.0f;    // c, mN·s/mm
  CellOrder order = default_order();
};

struct ContactParticles {
  std::span<const float> x, y, z;      // mm
  std::span<const float> vx, vy, vz;   // mm/s
  std::span<const uint32_t> fragment;  // fragment label per particle
  std::span<const uint8_t> boundary;   // 1: a boundary cell, takes part in contact
  // Optional: the particles with boundary set, ascending, when the caller already has them (a
  // parallel pass of its own); empty: fragment_contact walks `boundary` for them. With them,
  // optionally their box (build_grid's `box`: min x, y, z, max x, y, z, NaN left out).
  std::span<const uint32_t> members;
  const std::array<float, 6>* members_box = nullptr;
};

struct ContactScratch {
  Grid grid;
  std::vector<uint32_t> members;  // boundary particles
  // Per grid cell: smallest and largest fragment in it; with sub-cells, then per sub-cell (8 a
  // cell, from index cells on).
  std::vector<uint32_t> cell_lo, cell_hi;
  std::vector<uint32_t> fragment_slot;  // per slot (+ kPad): the fragment label
};

struct ContactStats {
  uint32_t particles = 0;  // boundary particles in the grid
  uint64_t pairs = 0;      // inter-fragment pairs within h, each counted once
};

// The scalar s of f_ij = s · (x_i − x_j) for r² = |x_i − x_j|² and vdotd = (v_i − v_j)·(x_i − x_j).
float pair_force_scale(const ContactParams& p, float r2, float vdotd);

// Adds the contact force on every boundary particle to fx, fy, fz (indexed like the inputs).
// fragment_count < 2: no work at all.
ContactStats fragment_contact(const ContactParticles& particles, uint32_t fragment_count,
                              const ContactParams& params, ContactScratch& scratch,
                              std::span<float> fx, std::span<float> fy, std::span<float> fz);

// The stiffness at which one pair closing at `relative_speed` (mm/s) with reduced mass
// `reduced_mass` (kg) and no damping stops at r = stop_fraction·h: ½μv² = k·h²·∫ĝ(u)du over
// [stop_fraction, 1]. The caller must also keep the explicit step stable: dt² · k/μ small.
float stiffness_to_stop(float relative_speed, float reduced_mass, float h,
                        float stop_fraction = 0.5f);

}  // namespace phaco::sph
