#pragma once
// The keratome blade as geometry (issue 4 item 2; seed 000 §6.1: "an angled keratome ... entering
// the cornea at the limbus at a shallow angle"). The blade is a flat plate of thickness t whose
// outline, in its own plane, is a pentagon:
//
//        left shoulder                  left heel
//          o-----------------------------o  -+-
//   tip  /                               |   |  W        --> d (advance)
//      o                                 |   |          |
//        \                               |   |          v  l (lateral: the blade's right)
//          o-----------------------------o  -+-
//        right shoulder                 right heel
//      |<-s->|
//      |<--------------- L ------------->|
//
// The two cutting edges run from the tip back to the shoulders at tip - s·d ± (W/2)·l, the sides
// run parallel to d back to the heels at tip - L·d ± (W/2)·l. The sections (section.hpp) use the
// mid-plane; the thickness is carried for contact and rendering.
//
// Conventions: `axis` d is the direction of advance; `lateral` l points to the blade's right as
// seen from the surgeon for a blade advancing toward the optical axis (l = d_horizontal × ẑ);
// normal = l × d (the blade's upper face). As a scenario tool pose (DESIGN.md §7: `pos` = tip,
// the shaft along the tool's local +z), d = −(q·ẑ) and l = q·ŷ.
//
// Reads nothing from the world; plain functions. Throws std::invalid_argument naming the field on
// bad input (these are edge functions, called once per frame, not in a hot loop).
#include "engine/core/math.hpp"
#include "engine/io/track.hpp"

namespace phaco::incision {

struct KeratomeShape {
  double width_mm = 2.4;      // W; eye file `tools.keratome_width_mm`
  double thickness_mm = 0.1;  // plate thickness
  double shoulder_mm = 1.5;   // s: tip to the shoulders along the axis (the bevel)
  double length_mm = 6.0;     // L: tip to the heels along the axis, > s
};

struct KeratomeBlade {
  Vec3 tip = Vec3::Zero();        // mm
  Vec3 axis = Vec3::UnitX();      // direction of advance (normalised by blade_frame)
  Vec3 lateral = -Vec3::UnitY();  // across the blade, ⟂ axis (orthogonalised by blade_frame)
  KeratomeShape shape;
};

// The blade's orthonormal frame after checking: d = axis/|axis|, l = lateral with its component
// along d removed, normalised; n = l × d.
struct BladeFrame {
  Vec3 tip = Vec3::Zero();
  Vec3 d = Vec3::UnitX();
  Vec3 l = Vec3::UnitY();
  Vec3 n = Vec3::UnitZ();
};

// Throws std::invalid_argument "keratome blade: <field> ..." for a non-finite tip, axis or lateral,
// a zero axis, a lateral (nearly) parallel to the axis, width/thickness/shoulder/length that are
// not finite or not positive (shoulder may be 0: a square tip), or length <= shoulder.
BladeFrame blade_frame(const KeratomeBlade& blade);

// The outline's five corners in order tip, right shoulder, right heel, left heel, left shoulder
// (a convex pentagon in the blade plane; with shoulder 0 the tip sits mid-way on a square front).
struct BladeOutline {
  Vec3 corner[5];
};
BladeOutline blade_outline(const BladeFrame& frame, const KeratomeShape& shape);

// A standard clear-corneal approach: the tip on the anterior corneal sphere (centre (0, 0,
// anterior_centre_z), radius anterior_radius_mm) at projected radius limbus_radius_mm -
// limbus_distance_mm, at the given clock hour (12 = +y, 3 = +x), pointing toward the optical axis
// and descending at entry_angle_deg below the iris plane; lateral along the limbus (l = d_h × ẑ).
// Advancing the tip along `axis` from here makes the incision.
struct IncisionApproach {
  double clock_hour = 9.0;          // any finite value; wrapped modulo 12
  double limbus_distance_mm = 0.3;  // > 0: inside the clear cornea
  double entry_angle_deg = 15.0;    // in (0, 90)
};
// Throws std::invalid_argument naming the field when a value is non-finite, the entry angle is
// outside (0, 90), or the tip radius is not in (0, anterior_radius_mm).
KeratomeBlade incision_start_blade(double anterior_centre_z, double anterior_radius_mm,
                                   double limbus_radius_mm, const IncisionApproach& approach,
                                   const KeratomeShape& shape = {});

// Clock hour (in (0, 12], 12 = +y, 3 = +x) of the projection of `p` on the xy plane; 12 on the
// axis itself.
double clock_hour_of(const Vec3& p);

// The blade of a keratome held at a scenario tool pose (pos = tip, shaft along local +z).
KeratomeBlade blade_from_tool_pose(const ToolPose& pose, const KeratomeShape& shape = {});

// The unit quaternion of a tool pose that holds the blade with this axis and lateral (inverse of
// blade_from_tool_pose). Throws like blade_frame on a degenerate axis or lateral.
Quat tool_quat_for_blade(const Vec3& axis, const Vec3& lateral);

}  // namespace phaco::incision
