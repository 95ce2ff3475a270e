#pragma once
// Phaco erosion of lens cells by Russian roulette (seed 002 §6, "the phaco-emulsificator can
// remove simplexes falling inside an influence cone with a distance threshold according to a
// Russian roulette scheme").
//
//              shaft (+z local)
//                  │
//                  ● apex = tip
//                 ╱│╲        a cell at distance d from the apex, at angle θ from the axis, is a
//                ╱ │ ╲       candidate when d ≤ reach and θ ≤ half_angle; each frame it is
//               ╱  │θ ╲      removed with probability
//              ╱   ▼axis╲      p = clamp(k · power · (1 − hardness) · w(d, θ) · dt, 0, 1)
//             ╱ (−z local)╲    w(d, θ) = (1 − d / reach) · (1 − θ / half_angle)
//            ╰─────────────╯ reach
//
// w is 1 at the apex on the axis and falls linearly to 0 at the distance threshold and at the
// cone's side, so the tip eats fastest straight ahead and the crater has no hard edge. `k` is a
// rate (1/s): at power 1, hardness 0, w 1 a cell survives one second with probability
// ≈ exp(−k). Power is the ultrasound power fraction 0..1, zero unless the pedal is in position 3.
// The draw for cell i in frame f is CounterRng(seed, stream).uniform(f, i): removal depends only
// on (seed, stream, frame, cell id, state), never on threads or on the order of evaluation.
//
// Reads: cells (x, y, z, alive, hardness), the phaco tool pose. Writes: the removed-id list only
// (removal itself is the simplex system's topology command).
#include <cstdint>
#include <span>
#include <vector>

#include "components/lens_cells.hpp"
#include "engine/core/math.hpp"
#include "engine/core/rng.hpp"
#include "engine/io/track.hpp"

namespace phaco::lens_tools {

struct PhacoTip {
  Vec3 apex = Vec3::Zero();    // mm, the tip
  Vec3 axis = -Vec3::UnitZ();  // unit, out of the tip (the shaft's −z local)
  double power = 0;            // ultrasound power fraction 0..1
};

struct ErosionSettings {
  double half_angle_rad = 0.6;  // cone half-angle (≈ 34°)
  double reach_mm = 1.0;        // distance threshold from the apex
  double rate_per_s = 60.0;     // k in p above
};

// Power fraction from the pedal: `setting` (0..1) in position 3 (pedal ≥ 3), else 0.
inline double ultrasound_power(double pedal, double setting) {
  return pedal >= 3.0 ? setting : 0.0;
}

// The tip from a tool pose: apex at pos, axis = quat · (0, 0, −1).
PhacoTip phaco_tip(const ToolPose& pose, double power_setting);

// w(d, θ) above; 0 outside the cone.
double erosion_weight(double distance_mm, double angle_rad, const ErosionSettings& s);

// p above for a cell at `cell` (mm) of the given hardness; 0 outside the cone. The roulette in
// erode() evaluates exactly this (in float).
float removal_probability(const Vec3f& cell, float hardness, const PhacoTip& tip,
                          const ErosionSettings& s, double dt_s);

// Per-call scratch, grown on first use and reused (no allocation once warm).
struct ErosionScratch {
  std::vector<uint32_t> ids;     // per chunk, the chunk's removed ids from its first index
  std::vector<uint32_t> counts;  // per chunk
};

// One frame of erosion: `removed` is overwritten with the ids (indices into `cells`) of alive cells
// the roulette removes this frame, sorted ascending. Capacity of `removed` is reused.
void erode(const CellSpans& cells, const PhacoTip& tip, const ErosionSettings& s,
           const CounterRng& rng, uint64_t frame, double dt_s, ErosionScratch& scratch,
           std::vector<uint32_t>& removed);

}  // namespace phaco::lens_tools
