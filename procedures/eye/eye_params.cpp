#include "procedures/eye/eye_params.hpp"

#include <cmath>
#include <fstream>
#include <nlohmann/json.hpp>
#include <stdexcept>

#include "engine/core/error.hpp"
#include "engine/io/json_reader.hpp"
#include "procedures/eye/eye_param_ranges.hpp"

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

// "" when `value` is in the range of `key` (or `key` has none); else what was expected and got.
std::string range_problem(const std::string& key, double value) {
  if (!std::isfinite(value) || value <= 0.0) {
    return "expected a finite positive number, got " + io::format_number(value);
  }
  const EyeParamRange* r = eye_param_range(key);
  if (r == nullptr || (value >= r->lo && value <= r->hi)) return {};
  return "expected a number in " + io::format_number(r->lo) + ".." + io::format_number(r->hi) +
         " (the physical range of " + key + "), got " + io::format_number(value);
}

}  // namespace

double EyeParams::get(const std::string& key) const {
  const auto it = values.find(key);
  if (it == values.end()) throw std::out_of_range("eye parameter '" + key + "' is not defined");
  return it->second;
}

// Every parameter of the standard eye and the physical range it may take, from an eye file, a
// drill's difficulty or a scenario's override (docs/eye_model.md, "Ranges"). The ranges hold the
// published spread of adult and child eyes (DESIGN.md §6) with a margin, and the model constants a
// stable, meaningful value; geometric consistency between parameters (the capsule inside the lens,
// the pupil inside the iris) is checked when meshes are made. A value outside is an input error
// before any mesh or step sees it.
const std::vector<EyeParamRange>& eye_param_ranges() {
  static const std::vector<EyeParamRange> ranges = {
      {"lens.equatorial_diameter_mm", 6, 12},
      {"lens.anterior_half_thickness_mm", 0.5, 4},
      {"lens.posterior_half_thickness_mm", 0.5, 5},
      {"lens.nucleus_fraction", 0.1, 0.95},
      {"lens.density_kg_m3", 500, 2000},
      {"capsule.thickness_mm", 0.002, 0.1},
      {"capsule.youngs_modulus_kpa", 100, 20000},  // children ~6 MPa, elderly 1.5-3 MPa
      {"capsule.ultimate_stress_kpa", 50, 10000},
      {"capsule.elongation_at_break", 0.01, 2},
      {"capsule.poisson_ratio", 0.01, 0.499},  // below 0.5: the membrane model divides by 1 - ν
      {"capsule.density_kg_m3", 500, 2000},
      {"capsule.radius_mm", 2, 6},
      {"capsule.perforation_force_mn", 1, 1000},
      {"capsule.rim_strength_mn", 1, 10000},
      {"capsule.rim_stiffness_mn_mm", 1, 10000},
      {"capsule.tear_energy_j_m2", 10, 100000},
      {"capsule_model.prestretch", 1e-4, 0.5},
      {"capsule_model.damping_per_s", 0.01, 1000},
      {"capsule_model.viscosity_per_s", 0.01, 1000},
      {"capsule_model.glue_stiffness_mn_mm", 1e-6, 10},
      {"capsule_model.gravity_mm_s2", 1e-3, 1e5},
      {"capsule_model.active_hops", 1, 64},
      {"capsule_model.wake_motion_mm", 1e-5, 1},
      {"capsule_model.wake_force_mn", 1e-4, 100},
      {"capsule_model.grasp_radius_mm", 0.01, 3},
      {"lens_model.ultrasound_power", 0.01, 1},  // a fraction of full power (lens_sculpting)
      {"lens_model.damping_torque_mn_mm", 1e-4, 100},
      {"lens_model.bag_damping_mn_mm_s", 1e-3, 1e4},  // viscous damping of the bag (lens_sculpting)
      {"lens_model.nucleus_hardness", 0.05, 1},       // as the difficulty setting (docs/drills.md)
      {"lens_model.vacuum_limit_mmhg", 50, 700},      // phaco machines: up to ~650 mmHg
      {"lens_model.aspiration_flow_ml_min", 5, 60},   // peristaltic pumps: 20-40 mL/min
      {"lens_model.crack_strength_mn", 1, 500},       // crack force at hardness 1 (nucleus_removal)
      {"haptic_model.active_hops", 1, 64},
      {"haptic_model.contact_radius_mm", 0.05, 10},
      {"haptic_model.lens_stiffness_mn_mm", 0.1, 1e4},
      {"haptic_model.patch_stiffness_mn_mm", 0.1, 1e4},
      {"haptic_model.cut_force_mn", 0.1, 1e3},  // the ultrasound probe's cut (haptic_lens_contacts)
      {"iris.z_mm", 0.5, 4},
      {"iris.pupil_diameter_mm", 1, 12},  // the iris's outer edge is checked with the geometry
      {"cornea.posterior_apex_z_mm", 2, 8},
      {"cornea.central_thickness_mm", 0.2, 1.5},
      {"cornea.anterior_radius_mm", 5, 12},
      {"cornea.posterior_radius_mm", 4, 11},
      {"cornea.limbus_diameter_mm", 9, 14},
      {"cornea.youngs_modulus_kpa", 10, 1e5},
      {"cornea.density_kg_m3", 500, 2000},
      {"globe.axial_length_mm", 15, 35},
      {"globe.radius_mm", 8, 18},
      {"tools.phaco_tip_diameter_mm", 0.2, 3},
      {"tools.keratome_width_mm", 0.5, 5},
      {"tools.cystotome_tip_mm", 0.05, 2},
      {"tool_eye.hand_stiffness_mn_mm", 1, 1e6},
      {"tool_eye.hand_rotational_stiffness_mn_mm_per_rad", 1, 1e8},
      {"tool_eye.tunnel_stiffness_mn_mm", 0.1, 1e5},
      {"tool_eye.tunnel_rotational_stiffness_mn_mm_per_rad", 0.01, 1e7},
      {"tool_eye.tunnel_free_angle_deg", 0.1, 60},
      {"tool_eye.tunnel_length_mm", 0.2, 5},
      {"tool_eye.entry_angle_deg", 1, 80},
      {"tool_eye.port_inset_mm", 0.01, 3},
      {"tool_eye.side_port_width_mm", 0.2, 5},
      {"tool_eye.cornea_stiffness_mn_mm", 0.1, 1e5},
      {"tool_eye.lens_stiffness_mn_mm", 0.1, 1e5},
      {"tool_eye.globe_rotational_stiffness_mn_mm_per_rad", 1, 1e8}};
  return ranges;
}

const EyeParamRange* eye_param_range(std::string_view key) {
  for (const EyeParamRange& r : eye_param_ranges()) {
    if (r.key == key) return &r;
  }
  return nullptr;
}

const std::vector<std::string_view>& required_eye_keys() {
  static const std::vector<std::string_view> keys = [] {
    std::vector<std::string_view> out;
    for (const EyeParamRange& r : eye_param_ranges()) out.push_back(r.key);
    return out;
  }();
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
      const std::string name = section + "." + key;
      if (const std::string problem = range_problem(name, v); !problem.empty()) {
        throw InputError(where + ": " + path + ": " + problem);
      }
      params.values[name] = v;
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
  if (const std::string problem = range_problem(key, value); !problem.empty()) {
    throw InputError(problem);
  }
  it->second = value;
}

}  // namespace phaco::eye
