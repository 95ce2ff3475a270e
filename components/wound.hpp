#pragma once
// The corneal wound a keratome leaves, as data (issue 4 item 2): its measures for scoring (seed 000
// §6.1: "the angle and size of insertion, the penetration depth") and the port it opens for later
// tool insertion, kept as a circular arc stored as its extrema radial versors (seed 001 §3.3).
// Frame and units: DESIGN.md §6 (mm; +z toward the surgeon; 12 o'clock = +y, 3 o'clock = +x).
// Filled by systems/incision (wound.hpp: update_wound / measure_wound).
#include <Eigen/Core>

#include "engine/core/math.hpp"

namespace phaco {

// Where a cut crosses one corneal surface (the anterior or the posterior sphere).
struct WoundSection {
  bool valid = false;          // the blade has crossed this surface
  Vec3 left = Vec3::Zero();    // mm, end on the blade's left (smaller lateral coordinate)
  Vec3 right = Vec3::Zero();   // mm, end on the blade's right
  Vec3 centre = Vec3::Zero();  // mm, middle of the cut arc, on the surface
};

struct CornealWound {
  bool incised = false;           // the blade's tip has crossed the anterior surface
  bool penetrated = false;        // ... and the posterior one: the tunnel opens into the chamber
  double width_mm = 0;            // |outer.right - outer.left|, widest outer section seen
  double inner_width_mm = 0;      // |inner.right - inner.left|, widest inner section seen
  double entry_angle_deg = 0;     // blade axis below the iris plane (z = const) at puncture
  double clock_hour = 0;          // outer centre in the microscope view, in (0, 12]; 12 = +y
  double limbus_distance_mm = 0;  // limbus radius - projected radius of outer.centre; > 0 = cornea
  double tunnel_length_mm = 0;    // |inner.centre - outer.centre|; 0 until penetrated
  double penetration_depth_mm = 0;  // deepest tip advance past the posterior sphere, along d
  WoundSection outer;               // on the anterior corneal sphere
  WoundSection inner;               // on the posterior corneal sphere
};

// The port as seed 001 §3.3 keeps it: a circular arc about the optical axis at radius `radius_mm`
// and height `z_mm`, from the radial versor `start` counter-clockwise (seen from +z) to `end`.
// The extrema are recomputed while the blade cuts, so the arc enlarges and partly reorients.
struct PortArc {
  bool open = false;                                 // no port until the blade has cut
  Eigen::Vector2d start = Eigen::Vector2d::UnitX();  // unit (x, y)
  Eigen::Vector2d end = Eigen::Vector2d::UnitX();    // unit (x, y); ccw from start
  double radius_mm = 0;                              // distance of the arc from the optical axis
  double z_mm = 0;                                   // height of the arc
};

}  // namespace phaco
