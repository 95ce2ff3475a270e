#pragma once
// The eye a finished procedure step leaves to the next (issue 20 item 1, docs/procedures.md):
//   incision     the main port at the cut's own site, width and tunnel (the outer cut's middle
//                to the inner's), and the cut cornea;
//   rhexis       the capsule still held at its rim (the torn disc is taken out, as a surgeon
//                does), in the shape it was left, and the opening's equivalent radius;
//   sculpting    the tets the probe removed: the next step's groove is that trench.
// What a step did not touch is left as the earlier steps left it.
#include <nlohmann/json.hpp>

#include "procedures/scene/carried_state.hpp"

namespace phaco {

struct Scene;

// Adds what `scene` (at the end of its step) changed to `state`.
void carry_out(Scene& scene, CarriedState& state);

// Whether the incision step cut into the anterior chamber (a main port exists); false for a scene
// without the incision's cutting.
bool incision_entered_chamber(Scene& scene);

// The carried state for the report: the port, the sizes of the surfaces, the rhexis radius, the
// trench's removed tets.
nlohmann::json carried_json(const CarriedState& state);

}  // namespace phaco
