#pragma once
// The depth cue (issue 24 item 2): a tool tip's height above the tissue under it, along the
// microscope's axis (−z, DESIGN.md §6), the trainee's substitute for stereopsis on a flat screen.
//
// The tissue is the eye's derived geometry (procedures/eye/eye_geometry, what the meshes are made
// from): the cornea between its posterior and anterior spheres inside the limbus, and the lens's
// two half-ellipsoids, whose anterior surface the capsule lies on (out to capsule_radius). Along
// the vertical through the tip each is an interval of z; the tip inside one is in that tissue
// (height < 0: how deep below its top), else its height is above the highest top below it.
// Closed form: a few square roots per tip, whatever the meshes' size.
#include "engine/core/math.hpp"
#include "engine/render/snapshot.hpp"
#include "procedures/eye/eye_geometry.hpp"

namespace phaco {

struct TipHeight {
  double height_mm = 0;  // NaN over no tissue
  render::Tissue under = render::Tissue::None;
};

// `capsule`: the scene has an anterior capsule (else the lens's surface is bare).
TipHeight tip_height(const eye::EyeGeometry& g, bool capsule, const Vec3& tip_mm);

// How the trainer shows a height: above the tissue, touching it (within one wheel click above
// its surface), or in it.
enum class HeightBand { None, Above, Touching, In };
HeightBand height_band(double height_mm);
inline constexpr double kTouchingMm = 0.1;

}  // namespace phaco
