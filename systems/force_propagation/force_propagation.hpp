#pragma once
// Force propagation model (FPM), seed 000 §5.1 after Choi, Sun & Heng (its ref. [23]): the fast,
// quasi-static alternative to integrating the whole membrane. "Deformation is considered as a
// sequential force transmission process with forces propagating from the surface contact points
// to their neighbouring nodes layer by layer at increasing topological distance."
//
//   layer 0   the sources: contact vertices whose position a tool imposed (grasp, push), or that
//             carry a point force; cut-path vertices after a cut (issue 4) are sources too
//   layer 1   their spring neighbours, found breadth-first over the spring graph
//   layer ℓ   neighbours of layer ℓ−1 not seen before
//
// One sweep relaxes layer 1, 2, ... in that order. Relaxing a node is one local Newton step on
// its springs with every other node held: x_i ← x_i + ω·K_ii⁻¹·f_i, where f_i is the net spring
// (plus external) force on i and K_ii = Σ_j [k'_ij·n̂n̂ᵀ + (t_ij/l_ij)·(I − n̂n̂ᵀ)] the 3×3 block of
// the stiffness at i (k' the axial tangent stiffness, t the tension). The transverse term t/l is
// what a pre-stretched membrane resists a push with; a scalar step f/Σk would underestimate that
// motion by the ratio t/(k·l), about the pre-strain, and crawl. Nodes already placed in this sweep
// are used at their new positions (Gauss–Seidel from the contact outward).
//
// The front: a sweep moves on to layer ℓ+1 only while layer ℓ still moved by more than
// tolerance_mm, and never past max_layers; nodes beyond the front are held where they are. Later
// sweeps repeat the relaxation inside the front (pushing it further out when its last layer still
// moves), until a whole sweep moves no node by more than tolerance_mm or `sweeps` are done. With
// enough layers and sweeps this is nonlinear Gauss–Seidel on the spring energy, so it converges
// to the static equilibrium; with few, it is the truncated, cheap response the seed uses.
//
// Cost follows the touched region: the breadth-first search grows one layer at a time as the
// front needs it, and the mesh-sized layer table in the scratch is reset by walking the touched
// list, not the mesh. Serial and deterministic: the visiting order is fixed by the graph's order.
//
// Reads: springs (i, j, rest_length, stiffness), particles (kind). Writes: particles (x, y, z) of
// free nodes within the front.
#include <cstdint>
#include <span>
#include <vector>

#include "components/particles.hpp"
#include "components/springs.hpp"

namespace phaco::force_propagation {

// The spring graph (components/springs.hpp) comes from springs::build_spring_graph.

struct PropagationSettings {
  int max_layers = 16;         // layers relaxed beyond the sources (topological distance)
  int sweeps = 4;              // outward sweeps at most
  double tolerance_mm = 1e-5;  // a layer that moves less does not push the front on; a sweep
                               // that moves nothing more ends the propagation
  double relaxation = 1.0;     // ω: 1 is plain Gauss–Seidel, up to ~1.9 over-relaxes
};

// Point forces on the sources (mN), one per source; a source with a force is relaxed under it
// instead of being held.
struct SourceForces {
  std::span<const float> fx, fy, fz;
};

struct PropagationResult {
  int layers_reached = 0;  // outermost layer relaxed
  int sweeps_done = 0;
  uint32_t nodes_touched = 0;     // nodes in layers 0..layers_reached
  uint64_t node_updates = 0;      // local relaxations performed (the work)
  double last_sweep_move_mm = 0;  // largest move in the last sweep
  double max_residual_mn = 0;     // largest net force left on a relaxed node
};

// Reused between calls; sized to the mesh once, then reset in time proportional to the touched
// region.
struct PropagationScratch {
  std::vector<int32_t> layer_of;      // per particle: layer, or −1 when not reached
  std::vector<uint32_t> order;        // touched nodes in breadth-first order
  std::vector<uint32_t> layer_begin;  // order[layer_begin[ℓ] .. layer_begin[ℓ+1]) is layer ℓ
  std::vector<float> ext_x, ext_y, ext_z;  // external force per order slot (sources only)
};

// Moves the free particles around `sources` toward equilibrium with the sources where they are
// (or under `forces`). Sources are particle indices (duplicates ignored). Anchored and scripted
// particles are never moved; they pass the propagation on.
PropagationResult propagate(Particles& particles, const Springs& springs, SpringLaw law,
                            const SpringGraph& graph, std::span<const uint32_t> sources,
                            const PropagationSettings& settings, PropagationScratch& scratch,
                            const SourceForces* forces = nullptr);

}  // namespace phaco::force_propagation
