#pragma once
// The standard eye (DESIGN.md §6) as a flat table of named numbers, loaded from
// data/eye/standard_eye.json. Units are in the key names ("capsule.youngs_modulus_kpa").
#include <filesystem>
#include <map>
#include <string>
#include <string_view>
#include <vector>

#include "procedures/eye/data_dir.hpp"

namespace phaco::eye {

struct EyeParams {
  std::map<std::string, double>
      values;  // "section.key" -> value, e.g. "capsule.youngs_modulus_kpa"

  // Throws std::out_of_range naming the key.
  double get(const std::string& key) const;
};

// Every key a standard eye file must define; load_eye_params rejects a file missing one of them.
const std::vector<std::string_view>& required_eye_keys();

// Throws InputError naming the file and the JSON path (e.g. "/lens/nucleus_fraction") on a
// missing file, invalid JSON, a missing key, a value that is not a finite positive number, or one
// outside its physical range (eye_param_ranges.hpp).
EyeParams load_eye_params(const std::filesystem::path& file);

// data_dir() / "eye" / "standard_eye.json".
EyeParams default_eye_params();

// Throws InputError "unknown eye parameter 'key' (known: ...)", or "expected a number in lo..hi
// (the physical range of key), got v" for a value outside the key's range (eye_param_ranges.hpp)
// or one that is not finite and positive. Geometric consistency (e.g. capsule radius inside the
// lens) is checked when meshes are made.
void apply_override(EyeParams& params, const std::string& key, double value);

}  // namespace phaco::eye
