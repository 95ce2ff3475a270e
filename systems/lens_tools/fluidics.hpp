#pragma once
// Phaco fluidics at the probe's port (issue 19): occlusion, the vacuum that builds on it and the
// fragment it holds.
//
//   occlusion  the port (a sphere of port_radius_mm at the tip) is covered when the alive cells of
//              one fragment inside it fill at least occlusion_fraction of its volume (cell
//              volumes summed: the same at every resolution level);
//   vacuum     first order toward its target, dP/dt = (P* − P)/τ. With the pedal ≥ 2 the target is
//              the vacuum limit when occluded (the pump keeps drawing on a closed line) and the
//              tip's flow resistance R·Q when open; with the pedal < 2 it is 0 (the line vents).
//              τ = C·P_limit/Q: a peristaltic pump at flow Q (mL/s) evacuating tubing of compliance
//              C (mL/mmHg) reaches the limit's scale in that time (≈ 0.7 s at 30 mL/min, 350
//              mmHg, C = 1e-3), as phaco machines' rise times;
//   holding    the occluding fragment is held when the vacuum's pull on the port, P·A (A the
//              port's area), exceeds its weight in the fluid and it is no heavier than a quadrant
//              (max_held_mass_fraction of the lens: an uncracked nucleus is held by the bag and the
//              zonules, not by the tip). It stays held, the port open or not, while a cell of it
//              is within hold_reach_mm of the port and the vacuum, decaying once the port opens,
//              still outweighs it. A held fragment follows the tip and is fed into it: its
//              cells' velocities blend toward the tip's velocity plus a draw of its cell c nearest
//              the port onto it, v ← v + β (v_tip + u·min(|port − c|/τ_draw, v_feed) − v),
//              u = (port − c)/|port − c|, β = 1 − exp(−r·dt) (as the hook's drag); shape matching
//              keeps it rigid. With ultrasound the held fragment is emulsified at the port at
//              emulsify_rate_mm3_s × power, its cells nearest the port first (fragment_lens).
//              Applied after the medium's step, to this step's move too
//              (x += dt·Δv): the vacuum carries the held fragment's weight. v_feed is how fast the
//              flow brings a held fragment onto the port (the emulsate and what fits the port go;
//              the rest presses on the tip).
// Reads: cells (x, y, z, alive, volume, mass), fragment labels and members. Writes: the held
// fragment's cells (velocity and this step's move), the vacuum.
#include <cstdint>
#include <span>
#include <vector>

#include "components/lens_cells.hpp"
#include "engine/core/math.hpp"

namespace phaco::lens_tools {

inline constexpr double kKpaPerMmhg = 0.133322;  // 1 mmHg = 133.322 Pa; 1 kPa = 1 mN/mm²

struct FluidicsSettings {
  double vacuum_limit_mmhg = 350;                // the machine's vacuum limit
  double flow_ml_min = 30;                       // aspiration flow
  double compliance_ml_per_mmhg = 1e-3;          // C: tubing and cassette
  double open_resistance_mmhg_per_ml_min = 1.0;  // R: vacuum at the open tip per unit flow
  double port_radius_mm = 0.45;                  // the tip's port (0.9 mm tip)
  double occlusion_fraction = 0.25;              // of the port sphere's volume
  double max_held_mass_fraction = 0.4;           // of the lens's mass
  double draw_rate_per_s = 600;                  // r in β: the held fragment follows at once
  double draw_time_s = 0.05;                     // τ_draw
  double feed_speed_mm_s = 20;                   // v_feed
  double hold_reach_mm = 1.5;                    // held while this close (the aspirator's reach)
  double emulsify_rate_mm3_s = 12;               // of soft lens at full power (held fragment)
  double gravity_mm_s2 = 892;                    // buoyancy-reduced g (lens_tools::Medium)
};

// τ = C·P_limit/Q in seconds.
double vacuum_rise_time_s(const FluidicsSettings& s);

// One step of dP/dt = (P* − P)/τ, exact for a constant target over dt.
double step_vacuum(double vacuum_mmhg, bool aspirating, bool occluded, const FluidicsSettings& s,
                   double dt_s);

// The pull of the vacuum on the port, mN.
double holding_force_mn(double vacuum_mmhg, const FluidicsSettings& s);

struct PortCover {
  uint32_t fragment = 0xffffffffu;  // the fragment filling most of the port
  double fraction = 0;              // its covered fraction of the port sphere's volume
  bool occluded = false;
};

// `per_fragment` is scratch (grown to the fragment count, reused).
PortCover port_cover(const CellSpans& cells, std::span<const float> volume,
                     std::span<const uint32_t> label, uint32_t fragments, const Vec3& port,
                     const FluidicsSettings& s, std::vector<double>& per_fragment);

// Blends the velocities of `members` (one fragment's cells) toward following the tip and drawing
// `nearest` (its cell nearest the port) onto `port`, and moves them by the change over this step.
void draw_to_tip(const CellSpans& cells, std::span<const uint32_t> members, const Vec3& port,
                 const Vec3& tip_velocity, const Vec3& nearest, const FluidicsSettings& s,
                 double dt_s);

}  // namespace phaco::lens_tools
