#pragma once
// Publish phase, the lens's half of a tool's haptic model (issue 19 item 5): the lens material
// near each tool's tip as contact spheres (components/haptic_model.hpp, HapticTool::sphere_*),
// for any tool — the sculpting probe, a second instrument, the chopper when it lands — and the
// tool's held fragment (components/held_fragment.hpp) when the drill's aspiration fills one.
//
//   lens.model tets       the alive tets with an exposed face (TetTopology's surface list) whose
//                         spheres come within haptic_model.contact_radius_mm of the tip sphere,
//                         found with the sculpting's own broadphase (octree or btDbvt over the
//                         rest shape), turned by the nucleus angle into the world
//   lens.model fragments  the alive simplex cells with an external face, at their current centres,
//                         less the held fragment's own cells. The lens has no spatial index (its
//                         cells are in tet order, not space order): one scan of the cell centres
//                         per frame for every tool at once (scan_lens_cells), since the scan is
//                         bound by reading the centres (level 3, 52k cells: 0.17 ms per tool per
//                         frame scanned alone, the expert's two tips both inside the nucleus)
//
// Each sphere: the element's centroid, its equal-volume radius (3V/4π)^⅓, and the stiffness
// k = k_f·h/0.5 — seed 003 §E.5's k_f (haptic_model.lens_stiffness_mn_mm) at the standard
// nucleus hardness h = 0.5, in proportion to the hardness (lens_model.nucleus_hardness; the
// cortex at half of it, as the fragment lens has it). Why k_f and not a tissue modulus: what the
// hand feels pushing a nucleus is the whole nucleus held in its bag (seed 000 §5.4 turns it, seed
// 003 renders it with k_f); a Hertz contact of the 0.45 mm tip on lens tissue is far softer
// (G from ~10 Pa in young nuclei to ~10⁴ times more at 78 years, Weeber et al. 2007, Graefes Arch
// Clin Exp Ophthalmol 245:1357), so the cell-level stiffness is not the felt one.
//
// Under ultrasound (the phaco probe at pedal 3) the tip cuts: the material's whole reaction is
// bounded by cut_force = haptic_model.cut_force_mn · (h / 0.5) / power (a harder nucleus or less
// power: more push needed), the rest of the press goes into the cut (seed 000 §5.3 removes what
// the tip reaches at the next frame).
//
// Nearest first, at most kHapticMaxSpheres. Reads: tools.pose, tools.held, lens.sculpting,
// lens.tets, lens.cells. Allocation-free once the scratch has grown.
#include <cstdint>
#include <span>
#include <utility>
#include <vector>

#include "components/haptic_model.hpp"
#include "engine/core/math.hpp"
#include "engine/ecs/world.hpp"

namespace phaco {

struct Scene;

struct HapticLensSettings {
  double reach_mm = 1.0;          // haptic_model.contact_radius_mm
  double stiffness_mn_mm = 100;   // k_f at the standard hardness
  double cut_force_mn = 20;       // haptic_model.cut_force_mn at standard hardness, power 1
  double nucleus_hardness = 0.5;  // lens_model.nucleus_hardness
  double ultrasound_power = 1.0;  // lens_model.ultrasound_power
};

struct HapticLensScratch {
  std::vector<uint32_t> queue, candidates;
  std::vector<std::pair<float, uint32_t>> near;  // gap to the tip (mm), element
  // The mean equal-volume radius (mm) of the tets lens of `tets_of` tets: where the search for
  // the nearest surface tets starts, and its margin. Found once per lens.
  double mean_radius_mm = 0.0;
  uint32_t tets_of = 0;
  // The largest equal-volume radius (mm) of the fragment lens's `cells_of` cells (their volumes
  // never change): a cell farther from the tip than the reach plus this has no sphere within it.
  double max_cell_radius_mm = 0.0;
  uint32_t cells_of = 0;
  std::vector<double> cell_radius_mm;  // each cell's equal-volume radius, found with the largest
  // The fragment lens's cells near each tool's tip, from scan_lens_cells: ids ascending, those
  // whose centre the float test puts within the tool's reach plus max_cell_radius_mm.
  // A tool's entry is used once (fill_lens_contacts takes it), so a later frame never reads a
  // scan of cells that have moved since.
  std::vector<Entity> scanned_tools;
  std::vector<std::vector<uint32_t>> scanned_cells;  // a slot per cell, the first count used
  std::vector<uint32_t> scanned_count;
  std::vector<uint32_t> cells_scanned_alone;  // a tool scan_lens_cells did not cover
};

HapticLensSettings haptic_lens_settings(const Scene& scene);

// True when the scene's lens is one the tools change (sculpted or fragmenting): its spheres
// replace the analytic lens of seed 003 §E.5.
bool has_sculptable_lens(const Scene& scene);

// A fragment lens: one pass over the cell centres finds the cells near every tool's tip (the
// scene's tools, each with its tip radius), kept in the scratch for fill_lens_contacts this frame.
// Call it after the tools moved and the lens stepped, before the tools' fill_lens_contacts; a tool
// it did not scan for is scanned alone there. Other lenses: nothing.
void scan_lens_cells(const Scene& scene, std::span<const Entity> tools,
                     std::span<const double> tip_radius_mm, const HapticLensSettings& settings,
                     HapticLensScratch& scratch);

// Fills t's spheres, cut force and held fragment for the tool entity `tool` (tip at its pose).
void fill_lens_contacts(const Scene& scene, Entity tool, const HapticLensSettings& settings,
                        HapticLensScratch& scratch, HapticTool& t);

}  // namespace phaco
