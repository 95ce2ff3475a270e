#pragma once
// The nucleus_removal drill's start state (issue 19): a nucleus already grooved by a cross-shaped
// trench, as the phaco_sculpting drill's targets ask (DESIGN.md §6: two trenches crossing at 90°
// through the centre, about 1.5 tip diameters wide and 80 % of the nucleus deep). The cells whose
// rest centres lie in either trench's slab are removed with the simplex removal primitive, so the
// start state is what a sculpting run leaves, without running one.
//
//            arm ──────────────┐                  a cell is in a trench when, in the lens's plane,
//       ┌────────────────────┐ │ width             it lies within width/2 of the arm's line and
//       │        ╳ centre    │ ┴                   within arm_length of the centre along it, and
//       └────────────────────┘                     deeper than the anterior surface but above the
//                                                 trench floor: z > top − depth·(top − bottom) of
//                                                 the nucleus at its (x, y) (half-ellipsoids)
#include <cstdint>
#include <vector>

#include "components/simplices.hpp"
#include "engine/core/math.hpp"

namespace phaco::lens {

struct CrossGroove {
  Vec3 centre_mm = Vec3::Zero();  // only x, y: the cross's centre on the lens
  double first_angle_deg = 0;     // the first trench's direction from +x
  double arm_length_mm = 2.5;     // centre to each trench end
  double width_mm = 1.35;         // 1.5 tip diameters
  double depth_fraction = 0.8;    // of the nucleus's thickness at the cell's (x, y)
  // The nucleus: half-ellipsoids about the origin (DESIGN.md §6, the inner 70 % of the lens).
  double nucleus_radius_mm = 3.29, nucleus_anterior_mm = 1.26, nucleus_posterior_mm = 1.89;
};

// Ids of the alive cells in the groove, ascending (rest centres).
std::vector<uint32_t> groove_cells(const SimplexCells& cells, const CrossGroove& groove);

}  // namespace phaco::lens
