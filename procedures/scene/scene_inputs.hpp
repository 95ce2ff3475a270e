#pragma once
// What a scene is built from besides its meshes, read and checked (issue 18): the drill file,
// each hand's tool against it, the difficulty, the eye parameters (eye file, then difficulty, then
// the scenario's overrides, each in its range, and the eye's geometry consistent) and the method
// keys. build_scene starts with it and `phaco validate` runs it. Not yet here: the method values
// ("capsule.integrator": "xyz", capsule.cg_tolerance, "tools.ports" without the drill's port
// sites), still refused only when the scene is built (exit 2, never 1).
#include "engine/io/drill_file.hpp"
#include "engine/io/scenario.hpp"
#include "procedures/eye/eye_params.hpp"

namespace phaco {

struct SceneInputs {
  DrillFile drill;
  DifficultySettings difficulty;  // the level's settings with the scenario's over them
  eye::EyeParams params;          // eye file, then difficulty, then the scenario's overrides
};

// Throws InputError naming the scenario (or drill) file and the field.
SceneInputs check_scene_inputs(const Scenario& scenario);

}  // namespace phaco
