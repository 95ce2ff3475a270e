#include "procedures/eye/eye_params.hpp"

#include <cmath>
#include <cstdlib>
#include <fstream>
#include <nlohmann/json.hpp>
#include <stdexcept>

#include "engine/core/error.hpp"

#ifndef PHACO_DATA_DIR
#error "PHACO_DATA_DIR must be defined by the build (procedures/CMakeLists.txt)"
#endif

namespace phaco::eye {
namespace {

std::string known_keys(const EyeParams& params) {
  std::string out;
  for (const auto& [key, value] : params.values) {
    if (!out.empty()) out += ", ";
    out += key;
  }
  return out;
}

}  // namespace

double EyeParams::get(const std::string& key) const {
  const auto it = values.find(key);
  if (it == values.end()) throw std::out_of_range("eye parameter '" + key + "' is not defined");
  return it->second;
}

const std::vector<std::string_view>& required_eye_keys() {
  static const std::vector<std::string_view> keys = {
      "lens.equatorial_diameter_mm",
      "lens.anterior_half_thickness_mm",
      "lens.posterior_half_thickness_mm",
      "lens.nucleus_fraction",
      "lens.density_kg_m3",
      "capsule.thickness_mm",
      "capsule.youngs_modulus_kpa",
      "capsule.ultimate_stress_kpa",
      "capsule.elongation_at_break",
      "capsule.poisson_ratio",
      "capsule.density_kg_m3",
      "capsule.radius_mm",
      "capsule.perforation_force_mn",
      "capsule.rim_strength_mn",
      "capsule.tear_energy_j_m2",
      "capsule_model.prestretch",
      "capsule_model.damping_per_s",
      "capsule_model.viscosity_per_s",
      "capsule_model.glue_stiffness_mn_mm",
      "capsule_model.gravity_mm_s2",
      "capsule_model.active_hops",
      "capsule_model.wake_motion_mm",
      "capsule_model.wake_force_mn",
      "capsule_model.grasp_radius_mm",
      "lens_model.ultrasound_power",
      "lens_model.damping_torque_mn_mm",
      "lens_model.push_force_per_mm_mn_mm",
      "lens_model.nucleus_hardness",
      "haptic_model.active_hops",
      "haptic_model.contact_radius_mm",
      "haptic_model.lens_stiffness_mn_mm",
      "haptic_model.patch_stiffness_mn_mm",
      "iris.z_mm",
      "iris.pupil_diameter_mm",
      "cornea.posterior_apex_z_mm",
      "cornea.central_thickness_mm",
      "cornea.anterior_radius_mm",
      "cornea.posterior_radius_mm",
      "cornea.limbus_diameter_mm",
      "cornea.youngs_modulus_kpa",
      "cornea.density_kg_m3",
      "globe.axial_length_mm",
      "globe.radius_mm",
      "tools.phaco_tip_diameter_mm",
      "tools.keratome_width_mm",
      "tools.cystotome_tip_mm",
      "tool_eye.hand_stiffness_mn_mm",
      "tool_eye.hand_rotational_stiffness_mn_mm_per_rad",
      "tool_eye.tunnel_stiffness_mn_mm",
      "tool_eye.tunnel_rotational_stiffness_mn_mm_per_rad",
      "tool_eye.tunnel_free_angle_deg",
      "tool_eye.tunnel_length_mm",
      "tool_eye.entry_angle_deg",
      "tool_eye.port_inset_mm",
      "tool_eye.side_port_width_mm",
      "tool_eye.cornea_stiffness_mn_mm",
      "tool_eye.lens_stiffness_mn_mm",
      "tool_eye.globe_rotational_stiffness_mn_mm_per_rad"};
  return keys;
}

EyeParams load_eye_params(const std::filesystem::path& file) {
  const std::string where = file.string();
  std::ifstream in(file);
  if (!in) throw InputError(where + ": cannot open eye parameter file");
  nlohmann::json doc;
  try {
    doc = nlohmann::json::parse(in);
  } catch (const nlohmann::json::parse_error& e) {
    throw InputError(where + ": invalid JSON: " + e.what());
  }
  if (!doc.is_object()) throw InputError(where + ": top level must be an object of sections");

  EyeParams params;
  for (const auto& [section, body] : doc.items()) {
    if (!body.is_object()) {
      throw InputError(where + ": /" + section + " must be an object of \"key\": number pairs");
    }
    for (const auto& [key, value] : body.items()) {
      const std::string path = "/" + section + "/" + key;
      // Non-finite numbers cannot appear in strict JSON, so a number here is finite; zero and
      // negative values are rejected because every eye quantity is a size, modulus or count.
      if (!value.is_number()) throw InputError(where + ": " + path + " must be a number");
      const double v = value.get<double>();
      if (!std::isfinite(v) || v <= 0.0) {
        throw InputError(where + ": " + path + " must be a finite positive number, got " +
                         value.dump());
      }
      params.values[section + "." + key] = v;
    }
  }
  for (const auto key : required_eye_keys()) {
    if (!params.values.count(std::string(key))) {
      const auto dot = key.find('.');
      throw InputError(where + ": missing /" + std::string(key.substr(0, dot)) + "/" +
                       std::string(key.substr(dot + 1)));
    }
  }
  return params;
}

EyeParams default_eye_params() {
  return load_eye_params(data_dir() / "eye" / "standard_eye.json");
}

void apply_override(EyeParams& params, const std::string& key, double value) {
  const auto it = params.values.find(key);
  if (it == params.values.end()) {
    throw InputError("unknown eye parameter '" + key + "' (known: " + known_keys(params) + ")");
  }
  if (!std::isfinite(value)) {
    throw InputError("eye parameter '" + key + "' must be finite, got " + std::to_string(value));
  }
  if (value <= 0.0) {
    throw InputError("eye parameter '" + key + "' must be positive, got " + std::to_string(value));
  }
  it->second = value;
}

std::filesystem::path data_dir() {
  if (const char* env = std::getenv("PHACO_DATA_DIR"); env != nullptr && *env != '\0') {
    return std::filesystem::path(env);
  }
  return std::filesystem::path(PHACO_DATA_DIR);
}

}  // namespace phaco::eye
