#pragma once
// The physical range of every eye parameter (issue 18; docs/eye_model.md, "Ranges"). An eye file
// (load_eye_params), a drill's difficulty and a scenario's override (apply_override) may only set
// a parameter inside its range: a value outside is an InputError "expected a number in lo..hi
// (the physical range of KEY), got V", before any mesh or step sees it.
#include <string_view>
#include <vector>

namespace phaco::eye {

struct EyeParamRange {
  std::string_view key;  // "section.key", as in eye_params.hpp
  double lo, hi;         // inclusive, in the key's unit
};

// One row per key the standard eye requires (required_eye_keys), in the eye file's order.
const std::vector<EyeParamRange>& eye_param_ranges();
// The range of `key`, or nullptr for a key outside the standard eye (an eye file's extra keys need
// only be finite and positive).
const EyeParamRange* eye_param_range(std::string_view key);

}  // namespace phaco::eye
