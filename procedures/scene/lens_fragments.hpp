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
};

// "tets" or "fragments" from the scenario's methods (InputError for anything else).
std::string lens_model(const Scene& scene);

void add_lens_fragments(Scene& scene);

// Dynamics phase: reads tools.pose; writes lens.cells, lens.tets.
SystemDesc lens_fragments_system(Scene& scene);

nlohmann::json lens_fragments_summary(Scene& scene);

}  // namespace phaco
