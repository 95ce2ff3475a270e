#pragma once
// The corneal port as seed 001 §3.3 models it: "the cut is modeled as a circular arc and stored as
// its extrema radial versors. During the cutting stage, the extrema are constantly recomputed, in
// order to perform the cut enlargement and its partial reorientation."
//
// The port is the outer wound (the opening a tool must find). The arc lies at radius r from the
// optical axis and height z (update_wound: those of the widest outer section's ends, so the
// chord equals the wound width for a straight pass); its extrema are unit radial
// versors in the xy plane, from `start` counter-clockwise (seen from +z) to `end`. Each frame the
// blade cuts, widen_port replaces the arc by the smallest arc holding both the old arc and the
// new cut ends (the cut never heals, so the port only grows; sweeping the blade sideways grows it
// on that side, which turns its middle: the "partial reorientation").
//
// For the tool-insertion work: port_size (chord and angle), port_passes (does a tool shaft point
// go through the port) and nearest_on_port (the anchor of a constraint spring).
//
// Reads/writes: PortArc (components/wound.hpp). No allocation; bad input throws
// std::invalid_argument naming the field.
#include "components/wound.hpp"
#include "engine/core/math.hpp"

namespace phaco::incision {

// Counter-clockwise angle from start to end, in [0, 2π).
double port_sweep_rad(const PortArc& port);

struct PortSize {
  double angle_rad = 0;  // sweep
  double chord_mm = 0;   // 2·r·sin(angle/2)
  double arc_mm = 0;     // r·angle
};
PortSize port_size(const PortArc& port);

// Opens (or widens) the port to hold the radial directions of the cut ends `a` and `b` (any
// order; the arc between them is the shorter one), and sets the radius and height to the ends'
// means (so for ends at equal radius and height the port's chord is |a − b|). Throws on
// non-finite points or ends on the optical axis; the port is unchanged then.
void widen_port(PortArc& port, const Vec3& a, const Vec3& b);

struct PortTolerance {
  double radial_mm = 0.3;   // |radius of the point − r|
  double z_mm = 0.3;        // |z of the point − z|
  double lateral_mm = 0.0;  // slack beyond the extrema, along the arc
};

// Whether `point` lies within the arc's angular span (plus lateral slack) and within the radial
// and height tolerances. False while the port is closed. Throws on a non-finite point or negative
// tolerances.
bool port_passes(const PortArc& port, const Vec3& point, const PortTolerance& tolerance = {});

// The point of the arc nearest `point`: its own angle clamped into the span (to the nearer
// extremum when outside), at the arc's radius and height. A point on the axis maps to the arc's
// middle. Throws on a closed port or a non-finite point.
Vec3 nearest_on_port(const PortArc& port, const Vec3& point);

// The arc's middle point (mm).
Vec3 port_middle(const PortArc& port);

}  // namespace phaco::incision
