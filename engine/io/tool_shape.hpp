#pragma once
// Where an instrument's shaft runs from its tip (issue 20 item 2). A pose is the tip and the
// shaft's direction; for a straight instrument (forceps, probe, aspirator, keratome) the shaft's
// axis is the line through the tip, but a bent point puts it beside the tip: the cystotome's 27 G
// needle is bent at a right angle 0.3 mm from its point, the chopper's and the Sinskey hook's ends
// 1 mm. The drawn instrument (engine/render/procedural), the pivot in a port
// (procedures/scene/port_pivot), the ports' equilibrium and metrics (systems/tool_eye,
// procedures/scene/tool_ports), the port a haptic device feels (systems/haptic_model) and the
// shaft pressing the rhexis rim (procedures/scene/rim_tear) all take the shaft from here, so they
// cannot disagree on where it passes.
#include "engine/core/math.hpp"
#include "engine/io/scenario.hpp"
#include "engine/io/track.hpp"

namespace phaco {

inline constexpr double kCystotomeBendMm = 0.3;  // DESIGN.md §6: the cystotome's bent tip
inline constexpr double kChopperBendMm = 1.0;    // chopper and hook: a 1 mm bent end

// From the tip to the shaft's axis, in the instrument frame (tip at the origin, the shaft along
// +z toward the handle): the bent point runs along local −y from the shaft to the tip.
inline Vec3 shaft_offset_local(ToolKind kind) {
  switch (kind) {
    case ToolKind::Cystotome:
      return Vec3(0.0, kCystotomeBendMm, 0.0);
    case ToolKind::Hook:
    case ToolKind::Chopper:
      return Vec3(0.0, kChopperBendMm, 0.0);
    default:
      return Vec3::Zero();
  }
}

// The shaft's axis of a tool at `pose`: the line through `point` (beside the tip, where the bend
// meets the shaft) along `direction` (unit, tip → handle).
struct ShaftAxis {
  Vec3 point = Vec3::Zero();       // mm
  Vec3 direction = Vec3::UnitZ();  // unit
};

inline ShaftAxis shaft_axis(const ToolPose& pose, ToolKind kind) {
  const Quat q = pose.quat.normalized();
  return {pose.pos + q * shaft_offset_local(kind), q * Vec3::UnitZ()};
}

}  // namespace phaco
