#pragma once
// Every `methods` key a scenario may set and the values it takes, in one table (issue 18): the
// scene's systems read their choice through it, and `phaco validate` checks every value with it
// before any mesh is built, so a file validate accepts is never refused by run for a method.
#include <string>
#include <string_view>
#include <vector>

#include "engine/io/drill_file.hpp"
#include "engine/io/scenario.hpp"

namespace phaco {

struct MethodSetting {
  std::string_view key;                   // e.g. "capsule.integrator"
  std::vector<std::string_view> choices;  // empty: a number in (0, 1) (capsule.cg_tolerance)
};

// The lens model a drill runs unless its scenario says: "fragments" for nucleus_removal (seed 002's
// fragmenting lens; the drill cannot run on the rigid tets), "tets" for the others.
std::string_view default_lens_model(Drill drill);

// The table, in the order docs/methods list them.
const std::vector<MethodSetting>& method_settings();
// The setting called `key`, or nullptr.
const MethodSetting* find_method_setting(std::string_view key);

// The scenario's value for `key` (a key of the table), `fallback` when it sets none. Throws
// InputError "FILE: methods["key"]: unknown choice 'x'; expected one of: ..." for a value not
// among the key's choices.
std::string method_value(const Scenario& scenario, std::string_view key, std::string_view fallback);

// Every value the scenario sets is one its key takes: choices among the table's, a tolerance a
// number in (0, 1), lens.broadphase/narrowphase only with the tetrahedral lens, and
// tools.ports measure/constrain only where the drill file gives both port sites. Throws
// InputError naming the scenario and methods["key"]. (Which keys a drill's scene has is
// check_scene_inputs's.)
void check_method_values(const Scenario& scenario, const DrillFile& drill);

}  // namespace phaco
