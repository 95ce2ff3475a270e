#pragma once
// The corneal wound over a whole keratome pass (issue 4 item 2; seed 000 §6.1 metrics "the angle
// and size of insertion, the penetration depth"; seed 001 §3.3 port arc). Each frame the blade is
// sectioned with both corneal spheres (section.hpp); the tracker keeps the widest outer (anterior)
// and inner (posterior) sections seen, the blade axis at puncture and the deepest penetration, so
// the measures describe the whole cut, not the last frame; and it widens the port arc.
//
//   width          = |outer.right − outer.left|            (widest outer section)
//   entry angle    = asin(−d_z) at puncture                 (d = unit blade axis; iris plane z = c)
//   clock hour     = atan2(x, y)·12/2π of outer.centre, in (0, 12]  (12 = +y, 3 = +x)
//   limbus dist.   = limbus radius − √(x² + y²) of outer.centre
//   tunnel length  = |inner.centre − outer.centre|
//   penetration    = max over frames of (tip − inner puncture)·d, once the tip is past the
//                    posterior sphere
// (centre = middle of the cut arc on that sphere; for a blade advanced straight along its axis
// with the lateral along the limbus, it is where the axis line crosses the sphere.)
//
// Reads: the keratome blade (tool pose), the cornea's spheres. Writes: WoundTracker (its
// CornealWound and PortArc). No allocation.
#include <cstdint>

#include "components/wound.hpp"
#include "engine/core/math.hpp"
#include "systems/incision/keratome.hpp"
#include "systems/incision/section.hpp"

namespace phaco::incision {

// The two corneal surfaces as spheres centred on the optical axis (eye::EyeGeometry's
// cornea_*_centre_z, cornea_*_radius, limbus_radius), in mm.
struct CorneaSpheres {
  double anterior_centre_z = 0;
  double anterior_radius_mm = 0;
  double posterior_centre_z = 0;
  double posterior_radius_mm = 0;
  double limbus_radius_mm = 0;
};

// Throws std::invalid_argument naming the field on a non-finite or non-positive value.
void check_spheres(const CorneaSpheres& spheres);

struct WoundTracker {
  BladeSection outer;                  // widest section with the anterior sphere so far
  BladeSection inner;                  // widest section with the posterior sphere so far
  bool punctured = false;              // the tip has crossed the anterior sphere
  Vec3 entry_axis = Vec3::Zero();      // unit blade axis at the first frame the tip was through
  Vec3 outer_puncture = Vec3::Zero();  // where the tip crossed the anterior sphere
  double penetration_depth_mm = 0;
  uint32_t frames = 0;          // updates so far
  uint32_t cutting_frames = 0;  // updates in which the blade crossed the anterior sphere
  CornealWound wound;           // measures from the above, refreshed every update
  PortArc port;                 // widened every update in which the blade crosses the cornea
};

// This frame's sections: the cut points the cutter consumes (left and right ends per surface).
struct WoundFrame {
  BladeSection outer;
  BladeSection inner;
};

// One frame: sections the blade with both spheres, keeps the maxima, refreshes the wound and the
// port. Throws std::invalid_argument (naming the field) on a bad blade or bad spheres; the tracker
// is left unchanged then.
WoundFrame update_wound(WoundTracker& tracker, const KeratomeBlade& blade,
                        const CorneaSpheres& spheres);

// The wound measures from an outer and an inner section (either may not touch), the unit blade
// axis at puncture and the penetration depth.
CornealWound measure_wound(const BladeSection& outer, const BladeSection& inner,
                           const Vec3& entry_axis, double penetration_depth_mm,
                           const CorneaSpheres& spheres);

}  // namespace phaco::incision
