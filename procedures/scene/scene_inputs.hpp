#pragma once
// What a scene is built from besides its meshes, read and checked (issue 18): the drill file,
// each hand's tool against it, the difficulty, the eye parameters (eye file, then difficulty, then
// the scenario's overrides, each in its range, and the eye's geometry consistent) and the method
// keys and values (procedures/scene/method_settings.hpp). build_scene starts with it and
// `phaco validate` runs it.
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
