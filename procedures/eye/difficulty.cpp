#include "procedures/eye/difficulty.hpp"

#include <algorithm>

namespace phaco::eye {

namespace {
// DESIGN.md §6's anchors: ~6 MPa in children, 1.5–3 MPa in the elderly.
constexpr double kYoungAge = 10, kYoungModulusKpa = 6000;
constexpr double kOldAge = 80, kOldModulusKpa = 1500;
}  // namespace

double capsule_modulus_for_age_kpa(double age_years) {
  const double slope = (kOldModulusKpa - kYoungModulusKpa) / (kOldAge - kYoungAge);
  return std::clamp(kYoungModulusKpa + slope * (age_years - kYoungAge), kOldModulusKpa,
                    kYoungModulusKpa);
}

void apply_difficulty(EyeParams& params, const DifficultySettings& s) {
  if (s.patient_age_years) {
    const double e = capsule_modulus_for_age_kpa(*s.patient_age_years);
    const double ratio = e / params.get("capsule.youngs_modulus_kpa");
    apply_override(params, "capsule.youngs_modulus_kpa", e);
    apply_override(params, "capsule.ultimate_stress_kpa",
                   params.get("capsule.ultimate_stress_kpa") * ratio);
    apply_override(params, "capsule.tear_energy_j_m2",
                   params.get("capsule.tear_energy_j_m2") * ratio);
  }
  if (s.anterior_bowing_kpa && *s.anterior_bowing_kpa > 0) {
    const double a = 0.5 * params.get("lens.equatorial_diameter_mm");
    const double c = params.get("lens.anterior_half_thickness_mm");
    const double radius_mm = a * a / c;
    const double tension_mn_mm = *s.anterior_bowing_kpa * radius_mm / 2.0;  // kPa = mN/mm²
    const double sheet_mn_mm =
        params.get("capsule.youngs_modulus_kpa") * params.get("capsule.thickness_mm");
    const double strain = tension_mn_mm * (1.0 - params.get("capsule.poisson_ratio")) / sheet_mn_mm;
    apply_override(params, "capsule_model.prestretch",
                   params.get("capsule_model.prestretch") + strain);
  }
  if (s.anterior_chamber_depth_mm) {
    apply_override(params, "cornea.posterior_apex_z_mm",
                   params.get("lens.anterior_half_thickness_mm") + *s.anterior_chamber_depth_mm);
  }
  if (s.nucleus_hardness)
    apply_override(params, "lens_model.nucleus_hardness", *s.nucleus_hardness);
}

}  // namespace phaco::eye
