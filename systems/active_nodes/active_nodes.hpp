#pragma once
// Active node set (seed 003 §III.D; seed 004 "constrain the deformation calculations to the
// locality of the tear area"): only particles within k hops (breadth-first over the spring graph)
// of a grabbed or contacted particle are integrated; the rest sleep where they are.
//
// A sleeping particle wakes when
//   - it is within k hops of a seed (grabbed / contacted particle), or
//   - the net force on it (all its springs plus external loads) exceeds `force_threshold_mn`
//     (checked on the sleeping frontier: particles next to the active set, the only sleeping ones
//     whose springs a step can change), or
//   - one of its neighbours moved more than `motion_threshold_mm` in the last step (|v|·dt).
// An active particle outside the seeds' ball stays awake while it still moves or is still loaded
// above the thresholds; otherwise it falls asleep (listed in `fell_asleep` so the caller can zero
// its velocity).
//
// Seed 003 reports k = 5 → 120 of 2005 nodes on its curvilinear mesh. On a grid where every
// node links to its 8 neighbours (the checkerboard-diagonal layout) the 5-hop ball is the 11×11
// square, 121 nodes; on a 4-neighbour grid it is the diamond of 2k² + 2k + 1 = 61.
//
// Cost: every update touches the previous set, the seeds' ball and their neighbours only; never
// the whole mesh (per-particle marks are cleared through the lists that set them). After warm-up
// (the largest set seen so far) nothing allocates.
//
// Reads: SpringGraph, seeds, particles (positions, velocities), springs, external forces.
// Writes: ActiveSet.
#include <cstdint>
#include <span>
#include <vector>

#include "components/particles.hpp"
#include "components/springs.hpp"

namespace phaco::active_nodes {

// The spring graph (components/springs.hpp) comes from springs::build_spring_graph and, after a
// cut or tear, springs::patch_spring_graph. A graph with another particle count than the last
// update's (a cut added some) restarts the set from the seeds, as a first use does; its marks are
// cleared through the old set and grown for the new particles, never reset over the whole body.

struct WakeInputs {
  // Positions and velocities after the last step; null: no wake rules (only the seeds' ball).
  const Particles* particles = nullptr;
  double dt_s = 0.0;  // the last step, for the motion |v|·dt
  double motion_threshold_mm = 1.0e-3;
  // Net force rule: the force on a particle is the sum over ALL its springs (from the graph, not
  // only the active ones, so a sleeping particle in balance stays asleep) plus `external`.
  const Springs* springs = nullptr;  // null: no force rule
  SpringLaw law = SpringLaw::Linear;
  const Forces* external = nullptr;  // optional loads (tool contact), mN, indexed by particle
  double force_threshold_mn = 1.0e-2;
};

struct ActiveSet {
  std::vector<uint32_t> particles;  // sorted; feeds Membrane::active
  std::vector<uint32_t>
      springs;  // sorted; springs with at least one active end; Membrane::active_springs
  std::vector<uint32_t> fell_asleep;  // sorted; active last update, asleep now
  uint32_t woken = 0;                 // particles active only through the wake rules this update
  // Scratch, sized to the particle count once; cleared through the lists above.
  std::vector<uint8_t> mark;      // 1 = active
  std::vector<uint8_t> previous;  // 1 = was active at the last update
  std::vector<uint32_t> queue, hops, spring_scratch, previous_list;
};

// Recomputes `set` from the seeds' k-hop ball and the wake rules (see the top of this file).
// Seeds ≥ the graph's particle count are ignored. Deterministic: the output depends only on the
// inputs, never on the previous call's internal order.
void update_active_set(const SpringGraph& graph, std::span<const uint32_t> seeds, uint32_t k_hops,
                       const WakeInputs& wake, ActiveSet& set);

// Drops every particle from the set (all sleep); keeps the scratch capacity.
void clear_active_set(ActiveSet& set);

}  // namespace phaco::active_nodes
