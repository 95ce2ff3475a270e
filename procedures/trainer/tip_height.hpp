#pragma once
// The depth cue (issue 24 item 2): a tool tip's height above the tissue under it, along the
// microscope's axis (−z, DESIGN.md §6), the trainee's substitute for stereopsis on a flat screen.
//
// The tissue is the eye's layout the drill detectors test against (procedures/scene/drill_metrics:
// the same eye parameters): the cornea between its posterior and anterior spheres inside the
// limbus, and the lens's two half-ellipsoids, whose anterior surface the capsule lies on. Along
// the vertical through the tip each is an interval of z; the tip inside one is in that tissue
// (height < 0: how deep below its top), else its height is above the highest top below it.
// Closed form: a few square roots per tip, whatever the meshes' size.
#include "engine/core/math.hpp"
#include "engine/render/snapshot.hpp"

namespace phaco {

namespace eye {
struct EyeParams;
}

struct TipHeightGeometry {
  double cornea_anterior_radius_mm = 7.8, cornea_anterior_apex_z_mm = 5.33;
  double cornea_posterior_radius_mm = 6.5, cornea_posterior_apex_z_mm = 4.8;
  double limbus_radius_mm = 5.8;
  double lens_equator_radius_mm = 4.7;
  double lens_anterior_mm = 1.8, lens_posterior_mm = 2.7;  // half-thicknesses about z = 0
  bool capsule = true;  // the lens's anterior surface carries the capsule
};

// From the scene's eye parameters (cornea.*, lens.*). Throws InputError on a missing key.
TipHeightGeometry tip_height_geometry(const eye::EyeParams& params, bool has_capsule);

struct TipHeight {
  double height_mm = 0;  // NaN over no tissue
  render::Tissue under = render::Tissue::None;
};

TipHeight tip_height(const TipHeightGeometry& g, const Vec3& tip_mm);

// How the trainer shows a height: above the tissue, touching it (within one wheel click above
// its surface), or in it.
enum class HeightBand { None, Above, Touching, In };
HeightBand height_band(double height_mm);
inline constexpr double kTouchingMm = 0.1;

}  // namespace phaco
