#include "procedures/incision/cornea_sheet.hpp"

#include "procedures/eye/eye_geometry.hpp"
#include "procedures/eye/eye_mesh.hpp"
#include "procedures/eye/resolution.hpp"

namespace phaco::corneal_incision {

incision::CorneaSpheres cornea_spheres(const eye::EyeParams& params) {
  const eye::EyeGeometry g = eye::eye_geometry(params);
  return {g.cornea_anterior_centre_z, g.cornea_anterior_radius, g.cornea_posterior_centre_z,
          g.cornea_posterior_radius, g.limbus_radius};
}

cut::MembraneMaterial cornea_material(const eye::EyeParams& params) {
  const double half_h = 0.5 * params.get("cornea.central_thickness_mm");
  cut::MembraneMaterial m;
  m.springs.sheet_modulus_mn_mm =
      params.get("cornea.youngs_modulus_kpa") * half_h;  // kPa·mm = mN/mm
  m.springs.prestretch = params.get("capsule_model.prestretch");
  m.springs.pretension = springs::Pretension::Cotangent;
  m.areal_density_kg_mm2 = params.get("cornea.density_kg_m3") * 1e-9 * half_h;  // kg/m³ -> kg/mm³
  return m;
}

incision::KeratomeShape eye_keratome(const eye::EyeParams& params) {
  incision::KeratomeShape s;
  s.width_mm = params.get("tools.keratome_width_mm");
  return s;
}

cut::MembraneSheet make_cornea_sheet(const eye::EyeParams& params, int level) {
  return cut::make_membrane_sheet(eye::make_cornea(params, eye::resolution_for_level(level)),
                                  cornea_material(params));
}

}  // namespace phaco::corneal_incision
