#pragma once
// The fragmenting lens in the phaco-sculpting scene (issue 5; seed 002): scenario method
// `lens.model = fragments` puts procedures/lens/fragment_lens in place of the rigid tetrahedral
// lens (`lens.model = tets`, the default, procedures/scene/lens_sculpting).
//
// Tools: the phaco probe emulsifies in its cone with ultrasound (pedal 3, power
// lens_model.ultrasound_power) and aspirates at its port from pedal 2 (300 mmHg, as a phaco
// handpiece does); a hook drags the cells in its cylinder. The lens sits in the capsular bag
// below the cornea with a 5.2 mm capsulorhexis (the previous drill's target) as its opening.
// Removed cells are removed from the lens body's tets too; the cells' centres enter the state
// hash.
//
// In the nucleus_removal drill (issue 19) the lens starts grooved by a cross-shaped trench
// (procedures/lens/nucleus_groove, from the drill's guidance.trench_cross), fluidics are on (the
// port occludes, the vacuum builds toward lens_model.vacuum_limit_mmhg at
// lens_model.aspiration_flow_ml_min, a held fragment follows the tip), and the chopper (left hand)
// and the probe crack a fragment they push apart across a trench (lens_model.crack_strength_mn ×
// nucleus hardness). The system also keeps the run's totals the drill's metrics read: CDE,
// aspiration time, chopper force, pieces.
#include <nlohmann/json.hpp>
#include <vector>

#include "engine/io/scenario.hpp"
#include "engine/schedule/system.hpp"
#include "procedures/lens/fragment_lens.hpp"

namespace phaco {

struct Scene;

struct LensFragments {
  lens::FragmentLens lens;
  CounterRng rng{0};
  double ultrasound_power = 1.0;
  double vacuum_mmhg = 300.0;
  std::vector<ToolPose> previous_pose;  // per scene tool, last frame (the hook's velocity)
  uint64_t frames_awake = 0;
  double ms_total = 0, ms_max = 0;
  // SPH fragment contact (seed 002 §6.1): particle pairs tested, over the frames, and the most in
  // one frame; fragments present, the most in one frame (the sweep's cost figures).
  uint64_t contact_pairs_total = 0, contact_pairs_max = 0;
  // The nucleus_removal drill (fluidics on).
  bool nucleus_removal = false;
  double grooved_volume_mm3 = 0, start_volume_mm3 = 0;  // the groove; the lens left after it
  double cde_pct_s = 0;  // Σ ultrasound power (%) × dt: cumulative dissipated energy
  double ultrasound_time_s = 0, aspiration_time_s = 0, occluded_time_s = 0, held_time_s = 0;
  double max_vacuum_mmhg = 0;
  double chopper_force_max_mn = 0, chopper_force_sum_mn = 0;  // over engaged frames
  uint64_t chopper_engaged_frames = 0;
  uint32_t pieces = 1, pieces_max = 1;  // fragments of at least kPieceMassFraction of the lens
};

// A fragment counts as a piece of nucleus (fragments_removed) from this fraction of the lens's
// mass up: a quadrant is ~0.15 of it; crumbs the roulette leaves are far below.
inline constexpr double kPieceMassFraction = 0.02;

// "tets" or "fragments" from the scenario's methods (InputError for anything else).
std::string lens_model(const Scene& scene);

void add_lens_fragments(Scene& scene);

// Dynamics phase: reads tools.pose; writes lens.cells, lens.tets.
SystemDesc lens_fragments_system(Scene& scene);

nlohmann::json lens_fragments_summary(Scene& scene);

}  // namespace phaco
