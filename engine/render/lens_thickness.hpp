#pragma once
// The lens's remaining thickness along the microscope's axis, as a square map over the eye's
// x, y (issue 19 item 4). The renderer turns it into the red reflex's brightness: light from the
// fundus crosses what is left of the lens on its way back to the microscope, so the reflex in a
// trench brightens as the nucleus under it thins (lens_reflex.hpp).
//
// How: every triangle of the lens's closed, outward-wound surface is rasterised into the map,
// adding +z where it faces the microscope (an entry into the lens, seen from above) and −z where
// it faces away (an exit). A vertical line crosses a closed surface as entry, exit, entry, exit…,
// so the sum is Σ (z_entry − z_exit): the solid length on the line, whatever the shape (trenches,
// overhangs, fragments apart). The map is in the body frame, the microscope's axis being its z: the
// stereo eyes and the globe turned by the ports tilt the real ray by a few degrees only.
//
// Why on the CPU and not a GPU pass (back-face minus front-face depth into a float target): on
// llvmpipe that pass costs a second rasterisation of the whole lens at full resolution every frame
// and every stereo view, while this map is rebuilt only when the lens changes (topology or
// positions), on ~20k triangles into 128² cells (about 1 ms), and the shader reads it with one
// filtered fetch. Sampled at cell centres with a top-left rule, so a line through a shared edge or
// vertex counts once.
#include <cstdint>
#include <span>
#include <vector>

#include "engine/render/snapshot.hpp"

namespace phaco::render {

struct ThicknessMap {
  int size = 0;           // cells per side
  float origin_x = 0;     // mm, the map's corner at its smallest x, y (cell (0, 0)'s outer corner)
  float origin_y = 0;     // mm
  float cell_mm = 1;      // mm, a cell's side
  std::vector<float> mm;  // size × size, row y then column x: thickness on the cell centre's line
  // size × size: the top surface's height on that line (mm; kNoSurface where the line misses the
  // lens), what the microscope sees there. Its slope shades the trench walls (lens_reflex.hpp).
  std::vector<float> top_z;
  float bottom_z = 0;  // mm, the lowest point of the bodies (the posterior pole)
};

inline constexpr float kNoSurface = -1e30f;

// Rebuilds `map` (size × size cells) from the triangles of `bodies`, which together must be a
// closed surface wound counter-clockwise seen from outside. The map covers the bodies' x, y extent
// with a margin of two empty cells, so a filtered fetch fades to zero at the lens's rim. Holes
// in the surface show as wrong thickness on the lines through them, never as NaN: every cell is
// clamped to [0, the bodies' z extent]. Allocates only when the size grows.
void build_thickness_map(std::span<const BodyView* const> bodies, int size, ThicknessMap& map);

// The map's thickness at (x, y), bilinear between cell centres, 0 outside (tests and the CPU).
float thickness_at(const ThicknessMap& map, float x, float y);

}  // namespace phaco::render
