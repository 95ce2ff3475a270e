#pragma once
// Cracking the nucleus with two instruments (issue 19; the divide-and-conquer crack): the phaco
// probe's tip and the chopper's tip inside a trench, each against one wall, moving apart, split the
// nucleus along the trench.
//
//        chopper ●→   ←wall | trench | wall→   ←● probe        (seen along the trench)
//                           |  mid ×  |
//                           n ──────→            plane through mid, normal n = (probe − chopper)
//
// What we chose, and why: a crack is brittle, so the model is one threshold, not a fracture
// mechanics solve. The nucleus between the walls resists the tips' spread like seed 003's lens
// contact, F = k·d (k the lens stiffness, mN/mm), with d the growth of the tips' separation since
// both first touched the same fragment with the trench between them. When F reaches the crack force
// F_c = strength · hardness (a harder, brunescent nucleus needs more force: nucleus hardness 0..1
// scales it, the drill's difficulty sets it), every internal link of that fragment whose two cells
// lie on opposite sides of the plane through the tips' midpoint with normal n is broken (the
// simplex system's break_link), and the fragment falls apart along the trench. The plane runs along
// the trench because the tips push across it. A crack needs:
//   - each tip touching the fragment: an alive cell of it within contact_radius_mm of the tip (the
//     fragment is that of the cell nearest the probe, else that nearest the chopper);
//   - the trench between them: no alive cell of that fragment within gap_radius_mm of their
//     midpoint (a piece of another fragment lying in the trench does not bridge it);
//   - the spread growing: d > 0 measured from the smallest separation while engaged (moving the
//     tips together re-arms the spring; letting go of the fragment disengages).
// Deterministic: the nearest cells are those of one pass in id order (a parallel scan over fixed
// chunks, merged in id order), for any thread count.
//
// Reads: cells (x, y, z, alive, hardness), fragment labels, neighbour links, the two tips.
// Writes: CrackState, the list of links to break (the caller applies them at its sync point).
#include <array>
#include <cstdint>
#include <span>
#include <utility>
#include <vector>

#include "components/lens_cells.hpp"
#include "engine/core/math.hpp"

namespace phaco::lens_tools {

struct CrackSettings {
  double stiffness_mn_mm = 100.0;  // k: the nucleus resisting the tips' spread
  double strength_mn = 40.0;       // crack force at hardness 1 (F_c = strength · hardness)
  double contact_radius_mm = 0.5;  // a tip touches a fragment with a cell centre this close
  double gap_radius_mm = 0.35;     // the midpoint is in the trench: no cell centre this close
};

struct CrackState {
  bool engaged = false;
  double rest_separation_mm = 0;  // smallest tip separation since engaging
  uint32_t fragment = 0xffffffffu;
};

struct CrackPush {
  bool engaged = false;  // both tips on one fragment, the trench between them
  double force_mn = 0;   // k·d while engaged
  double crack_force_mn = 0;
  bool crack = false;  // force reached the crack force this frame
  uint32_t fragment = 0xffffffffu;
  Vec3 mid = Vec3::Zero(), normal = Vec3::UnitX();  // the crack plane
};

// The cells a crack reads: positions, alive, hardness (CellSpans' columns) and fragment labels.
struct CrackCells {
  std::span<const float> x, y, z;
  std::span<const uint8_t> alive;
  std::span<const float> hardness;
  std::span<const uint32_t> label;  // fragment per cell
};

// One frame of the push: updates `state`, returns the force and, when it reached F_c, the plane.
CrackPush push_apart(const CrackCells& cells, const Vec3& probe_tip, const Vec3& chopper_tip,
                     const CrackSettings& s, CrackState& state);

// The links (cell, face) of `fragment` crossing the plane (each link once, from the cell on the
// negative side), in cell order. `out` is overwritten; its capacity is reused.
void links_across(const CrackCells& cells, std::span<const std::array<uint32_t, 4>> neighbour,
                  uint32_t fragment, const Vec3& mid, const Vec3& normal,
                  std::vector<std::pair<uint32_t, uint32_t>>& out);

}  // namespace phaco::lens_tools
