#pragma once
// The lens as simplex cells breaking into fragments (seed 002 §4 and §6): the second lens model of
// the phaco-sculpting scene, beside the rigid tetrahedral lens of seed 000.
//
// One step takes the seed's evolution steps (§4; numbered as there), each a system of its own,
// in this order:
//   2. erosion: the phaco tip's cone removes cells by Russian roulette (lens_tools), each removal
//      a simplex removal primitive (simplex), fragments relabelled where a removal may split one
//   3. tools: the hook drags the cells in its cylinder, the aspirator pulls those in its sphere
//      and takes in (removes) those that reach its port
//   1. environment: gravity (buoyancy-reduced) and viscosity, first-order Euler, which moves the
//      cells with the velocities the tools changed (lens_tools)
//   4. fragment contact: SPH repulsion between boundary cells of different fragments (sph), only
//      when there are at least two fragments, applied as a bounded move (fragment_lens.cpp says
//      why)
//   5. environment constraints: cornea and capsule spheres, inelastic (lens_tools)
//   6. shape matching: every fragment pulled toward its best rigid placement of its rest shape
//      (Horn's closed form, shape_match), the pull's displacement added to the velocities. Cells
//      a constraint moved this step weigh a thousand times their mass in the fit (seed 002 §6.1:
//      "the interacting cells are forced to assume a very big mass"), so the fragment settles
//      against the constraint instead of being pulled back through it.
// With `fluidics` (the nucleus_removal drill, issue 19) the probe's port occludes, builds vacuum
// and holds a fragment (lens_tools/fluidics.hpp), a cell at the port is taken in only when
// ultrasound is on or its fragment fits through the port, and the probe and the chopper crack a
// fragment they push apart across a trench (lens_tools/crack.hpp, simplex break_link).
// Mass is accounted: initial = alive + emulsified + aspirated + grooved (removed at the drill's
// start), each summed from the removed cells' masses as they go.
// Until a tool first touches the lens (a removal, a hook or aspirator contact) the lens is asleep:
// nothing moves and nothing is computed (model no more than the scene needs).
#include <array>
#include <cstdint>
#include <optional>
#include <span>
#include <utility>
#include <vector>

#include "components/fragments.hpp"
#include "components/lens_cells.hpp"
#include "components/simplices.hpp"
#include "engine/core/math.hpp"
#include "engine/core/mesh_data.hpp"
#include "engine/core/rng.hpp"
#include "systems/lens_tools/cell_dynamics.hpp"
#include "systems/lens_tools/constraints.hpp"
#include "systems/lens_tools/crack.hpp"
#include "systems/lens_tools/erosion.hpp"
#include "systems/lens_tools/fluidics.hpp"
#include "systems/shape_match/shape_match.hpp"
#include "systems/simplex/simplex_cells.hpp"
#include "systems/simplex/simplex_fragments.hpp"
#include "systems/sph/contact.hpp"

namespace phaco::lens {

struct FragmentLensSettings {
  lens_tools::ErosionSettings erosion;
  lens_tools::AspiratorSettings aspirator;
  lens_tools::HookSettings hook;
  lens_tools::Medium medium;
  lens_tools::EyeBounds bounds;
  shape_match::MatchSettings match;  // stiffness α
  sph::ContactParams contact;        // h, stiffness (m/dt² or more: the move is bounded), order
  double nucleus_hardness = 0.5;     // 0..1, cortex cells get half of it
  double capture_mm = 0.3;  // cells this close to an aspirating port are aspirated (removed)
  double density_kg_mm3 = 1.07e-6;
  bool fluidics = false;  // occlusion, vacuum, holding and cracking (the nucleus_removal drill)
  lens_tools::FluidicsSettings fluid;
  lens_tools::CrackSettings crack;
};

// The tools acting on the lens this step (absent = not in the scene or not acting).
struct LensTools {
  std::optional<lens_tools::PhacoTip> phaco;
  std::optional<lens_tools::Hook> hook;
  std::optional<lens_tools::Aspirator> aspirator;
  // With fluidics: the probe's tip and velocity, whether its pedal aspirates (≥ 2), and the
  // chopper's tip (cracking needs both tips).
  std::optional<Vec3> probe_tip;
  Vec3 probe_velocity = Vec3::Zero();  // mm/s
  bool aspirating = false;
  std::optional<Vec3> chopper_tip;
};

struct FragmentLensStats {
  uint32_t removed = 0;    // cells removed this step (emulsified or aspirated)
  uint32_t aspirated = 0;  // of which taken in by the aspirating port
  uint32_t fragments = 0;
  bool relabelled = false;
  uint32_t contact_particles = 0;
  uint64_t contact_pairs = 0;
  shape_match::LensPassStats match;
  // With fluidics.
  lens_tools::CrackPush push;  // the tips' push this step (force, engaged, crack)
  uint32_t links_broken = 0;
  bool occluded = false;
  bool held = false;  // a fragment follows the tip
  double vacuum_mmhg = 0;
  double cover_fraction = 0;
};

struct FragmentLens {
  FragmentLensSettings settings;
  SimplexCells cells;
  std::vector<float> vx, vy, vz;  // per cell, mm/s (positions are cells.x/y/z)
  std::vector<float> hardness;    // per cell, 0..1
  std::vector<uint8_t> contact;   // per cell: an environment constraint moved it this step
  Fragments fragments;
  simplex::FragmentScratch fragment_scratch;
  std::vector<Quat> rotations;  // per fragment, previous best rotation (continuity)
  std::vector<Vec3f> rest, current;
  std::vector<float> match_mass;  // per cell: mass, ×sph::kHeavyMassFactor while in contact
  std::vector<float> fx, fy, fz;
  std::vector<uint8_t> boundary;  // per cell: takes part in fragment contact this step
  std::vector<std::array<float, 6>> fragment_box;  // contact regions (fragment_lens.cpp)
  std::vector<uint32_t> fragment_order;
  std::vector<uint32_t> region_bin_first, region_bin_items;  // regions by bin
  std::vector<uint32_t> boundary_ids;  // the cells with boundary set, ascending (mark_boundary)
  std::vector<std::array<float, 6>> boundary_chunk_box;  // their box per collect_ids chunk
  std::array<float, 6> boundary_box{};                   // and over all of them
  std::vector<std::pair<uint32_t, std::array<float, 6>>> overlaps;
  std::vector<uint8_t> pushed;  // per cell: fragment contact moved it this step
  std::vector<uint32_t> fragment_of;
  sph::ContactScratch contact_scratch;
  lens_tools::ErosionScratch erosion;
  std::vector<uint32_t> removed;
  std::vector<simplex::Removal> removals;
  std::vector<uint32_t> scan_ids, scan_counts, scan_hits;   // parallel scans' scratch (collect_ids)
  std::vector<std::pair<float, uint32_t>> feed_candidates;  // (squared distance, cell)
  bool awake = false;
  // Fluidics and cracking (with settings.fluidics).
  double vacuum_mmhg = 0;
  uint32_t held_fragment = kNoSimplex;  // this step's label of the held fragment
  uint32_t held_cell = kNoSimplex;      // a cell of it: labels change as cells go
  Vec3 held_nearest = Vec3::Zero();     // its cell nearest the port, mm
  double feed_budget_mm3 = 0;           // ultrasound on the held fragment not yet spent
  lens_tools::CrackState crack_state;
  std::vector<std::pair<uint32_t, uint32_t>> crack_links;
  std::vector<double> cover_scratch;
  uint64_t cracks = 0, links_broken = 0;
  // Mass accounting, kg: initial = alive + emulsified + aspirated + grooved.
  double initial_mass_kg = 0, emulsified_mass_kg = 0, aspirated_mass_kg = 0, grooved_mass_kg = 0;
  // Totals.
  uint64_t steps = 0, cells_removed = 0, cells_aspirated = 0;
  double volume_removed_mm3 = 0;
  uint32_t max_fragments = 1;
};

// Cells from the lens tets (one per tet, region 1 = nucleus); one fragment.
FragmentLens make_fragment_lens(const TetMesh& mesh, const FragmentLensSettings& settings);

// Removes cells (simplex removal primitive) and relabels the fragments where one may have split;
// wakes the lens. What erosion does each step; also for scripted cuts (tests, the perf harness).
void remove_lens_cells(FragmentLens& lens, std::span<const uint32_t> cells,
                       FragmentLensStats& stats);

// Breaks the given internal links (cell, face) and relabels the fragments; wakes the lens.
// Returns the number of links broken.
uint32_t crack_lens(FragmentLens& lens, std::span<const std::pair<uint32_t, uint32_t>> links);

// Σ mass of the alive cells, kg (in cell order).
double alive_mass_kg(const FragmentLens& lens);

FragmentLensStats step_fragment_lens(FragmentLens& lens, const LensTools& tools,
                                     const CounterRng& rng, uint64_t frame, double dt_s);

}  // namespace phaco::lens
