#pragma once
// Where a keratome blade crosses a corneal surface (issue 4 item 2). Both corneal surfaces are
// spheres centred on the optical axis (procedures/eye: anterior and posterior caps joined at the
// limbus), so a blade's mid-plane meets each in a circle, and the cut the blade makes in that
// surface is the part of the circle inside the blade's outline (keratome.hpp).
//
//   blade plane ∩ sphere:  circle of centre c' = C − h·n, radius ρ = √(R² − h²), h = (C − tip)·n
//   outline edge A→B:      |A + t(B − A) − C|² = R², t ∈ [0, 1]  (a quadratic per edge)
//
// The section's ends are the outermost crossings of the outline's boundary by the sphere, ordered
// by the lateral coordinate v = (P − tip)·l: with the tip through and the shoulders out they lie
// on the two bevels (a short cut that grows as the blade advances); with the shoulders through,
// on the two sides (a cut of width ≈ W). Each frame these ends are the cut points from which the
// cutter grows two cut paths, left and right of the puncture (seed 000 §5.2). Over the whole cut
// the section is the corneal tunnel seed 001 §3.3 records (wound.hpp, port_arc.hpp).
//
// Degenerate cases, all without NaN: tip exactly on the sphere → a section of zero width at the
// tip; blade plane tangent to the sphere, or the circle grazing an edge → one point (left =
// right); the whole circle inside the outline (a sphere flat against the blade) → closed = true,
// ends at c' ∓ ρ·l. Bad input throws std::invalid_argument naming the field (blade_frame).
//
// Reads: a keratome blade (tool pose) and one sphere. Writes nothing. No allocation.
#include <cstdint>

#include "engine/core/math.hpp"
#include "systems/incision/keratome.hpp"

namespace phaco::incision {

enum class OutlineEdge : uint8_t { None, RightBevel, RightSide, Heel, LeftSide, LeftBevel };

struct BladeSection {
  bool touches = false;       // the sphere crosses the blade: there is a cut on this surface
  bool tip_inside = false;    // the tip is inside the sphere or on it
  bool closed = false;        // the whole circle lies inside the outline
  Vec3 left = Vec3::Zero();   // mm, on the sphere; the end with the smaller lateral coordinate
  Vec3 right = Vec3::Zero();  // mm, on the sphere; the larger lateral coordinate
  OutlineEdge left_edge = OutlineEdge::None;  // outline edge the left end lies on
  OutlineEdge right_edge = OutlineEdge::None;
  double left_v = 0, right_v = 0;  // mm, lateral coordinates of the ends
  Vec3 middle = Vec3::Zero();  // mm, on the sphere: middle of the cut arc (closed: its front point)
  double width_mm = 0;         // chord |right − left|
  double arc_mm = 0;           // length of the cut arc between the ends, along the circle
  double circle_radius_mm = 0;   // ρ
  bool has_puncture = false;     // the tip is inside or on the sphere
  Vec3 puncture = Vec3::Zero();  // where the axis line behind the tip crosses the sphere
};

// The section of `blade` with the sphere of centre (0, 0, sphere_centre_z) and radius
// sphere_radius_mm. Throws std::invalid_argument naming the field on a bad blade (blade_frame),
// a non-finite centre or a radius that is not finite and positive.
BladeSection blade_section(const KeratomeBlade& blade, double sphere_centre_z,
                           double sphere_radius_mm);

// Signed distance (mm) of the in-plane point (u, v) = ((P − tip)·d, (P − tip)·l) to the outline:
// positive inside, the smallest of the distances to the edge lines.
double outline_signed_distance(const KeratomeShape& shape, double u, double v);

}  // namespace phaco::incision
