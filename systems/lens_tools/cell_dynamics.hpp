#pragma once
// The lens cells' motion apart from shape matching and fragment contact (seed 002 §6): the
// aspirator attracts cells in an influence sphere, the hook drags cells in an influence cylinder,
// and "gravity and viscosity are applied to cells by a first-order Euler integration scheme":
//
//   v ← v + dt (g − c v)        then        x ← x + dt v
//
// (velocity first, so the tools' velocity changes of this frame move the cells this frame).
// Tools act on velocities only; integrate() is the one pass that moves positions. Dead cells
// (alive = 0) are skipped by every pass. Each pass is a parallel_for over cells writing only the
// cell's own entries: bit-identical for any thread count, no allocation.
//
// Reads: cells (x, y, z, mass, alive), aspirator / hook poses. Writes: cells (vx, vy, vz; x, y, z
// in integrate()).
#include "components/lens_cells.hpp"
#include "engine/core/math.hpp"
#include "engine/io/track.hpp"

namespace phaco::lens_tools {

// ---- aspirator ----------------------------------------------------------------------------------

struct Aspirator {
  Vec3 port = Vec3::Zero();  // mm, the aspiration port (the tool tip)
  double vacuum_mmhg = 0;    // 0 .. ~600
};

struct AspiratorSettings {
  double radius_mm = 1.5;        // influence sphere around the port
  double force_per_mmhg = 2e-8;  // mN per mmHg at the port; F = f·vacuum·(1 − d/R)²
};

// Pull toward the port: a cell at distance d < R gains dt·F/m along the unit direction to the
// port, F = force_per_mmhg · vacuum · (1 − d/R)² (zero at the sphere, largest at the port). The
// speed toward the port after the kick is capped at d/dt so a light cell next to the port stops at
// it instead of shooting through (explicit Euler on a 1/d-steep pull would otherwise oscillate).
// Cells with mass ≤ 0 are not moved.
void aspirate(const CellSpans& cells, const Aspirator& a, const AspiratorSettings& s, double dt_s);

// ---- hook ---------------------------------------------------------------------------------------

// The hook's cylinder surrounds the instrument as drawn: its bent end from the point `a` to the
// bend, then the shaft from the bend to `b` (a straight hook: bend = a).
struct Hook {
  Vec3 a = Vec3::Zero();         // mm, the point
  Vec3 bend = Vec3::Zero();      // mm, where the bent end meets the shaft
  Vec3 b = Vec3::UnitZ();        // mm, the shaft's end in the lens's reach
  Vec3 velocity = Vec3::Zero();  // mm/s, the hook's velocity this frame
};

struct HookSettings {
  double radius_mm = 0.3;          // cylinder radius around segment ab (capped ends)
  double drag_rate_per_s = 200.0;  // velocity blend rate r: β = 1 − exp(−r·dt)
  double shaft_length_mm = 1.0;    // the shaft above the bend, used by hook_from_poses
};

// The hook from this frame's and last frame's poses, as the instrument is drawn
// (engine/io/tool_shape.hpp): the 1 mm bent end from the tip to the shaft's axis, then the shaft
// along quat · +z for shaft_length_mm; velocity (pos − prev.pos)/dt. (It was the segment from the
// tip along +z: a line 1 mm beside the real shaft, through cells no part of the hook touches.)
Hook hook_from_poses(const ToolPose& pose, const ToolPose& prev, double dt_s,
                     const HookSettings& s);

// Distance from p to segment ab (a point when a = b).
double distance_to_segment(const Vec3& p, const Vec3& a, const Vec3& b);

// Drag: a cell within radius of the bent end [a, bend] or the shaft [bend, b] takes v ← v + β
// (v_hook − v), β = 1 − exp(−r·dt) (so the blend does not depend on how the frame is split: two
// half steps equal one full one).
void drag_with_hook(const CellSpans& cells, const Hook& h, const HookSettings& s, double dt_s);

// ---- gravity and viscosity ----------------------------------------------------------------------

struct Medium {
  // Gravity less buoyancy: the lens (≈ 1.1 g/cm³) in aqueous/viscoelastic (≈ 1.0 g/cm³) sinks with
  // g·(1 − 1.0/1.1) ≈ 892 mm/s² along −z (the patient lies supine; +z is toward the surgeon).
  Vec3 gravity = Vec3(0, 0, -892.0);  // mm/s²
  double viscosity_per_s = 20.0;      // c: velocity relaxation rate of a cell in the fluid
};

// One first-order Euler step: v += dt (g − c v); x += dt v.
void integrate(const CellSpans& cells, const Medium& m, double dt_s);

}  // namespace phaco::lens_tools
