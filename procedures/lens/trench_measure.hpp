#pragma once
// The divide-and-conquer trenches a sculpting left in the nucleus (seed 000 §6.3: number, width,
// depth, crossing angle), measured in the lens's own frame (the nucleus rotates between trenches).
//
// Each removed element carries the stroke it was removed in (a stroke = one continuous period of
// ultrasound). Strokes whose removed material runs the same way and overlaps are one trench (a
// trainee deepens a trench in several passes). Per trench, from the removed elements' centres
// weighted by their volumes:
//   axis      principal direction of the centres in the iris plane (x, y);
//   width     the spread across the axis: the 5th–95th percentile range of the signed distance to
//             the axis, divided by 0.9 (a uniform band of width w gives w);
//   depth     how far below the nucleus's anterior surface the deepest 2 % of the removed
//             material near the lens axis (within `core_radius_mm`) reaches, as a fraction of the
//             nucleus's thickness there.
// The crossing angle is the angle between the axes of the two largest trenches, in [0, 90].
#include <cstdint>
#include <span>
#include <vector>

#include "engine/core/math.hpp"

namespace phaco::lens {

struct NucleusShape {
  double equatorial_radius_mm = 0;  // nucleus semi-axis in x and y
  double anterior_mm = 0;           // nucleus anterior pole z
  double posterior_mm = 0;          // nucleus posterior pole z (< 0)
};

struct RemovedElement {
  Vec3 centre;  // mm, lens frame
  double volume_mm3 = 0;
  uint32_t stroke = 0;
};

struct Trench {
  Vec3 axis;    // unit, in the iris plane (z = 0)
  Vec3 centre;  // volume-weighted centre of the removed material, mm
  double width_mm = 0;
  double depth_mm = 0;        // below the nucleus's anterior surface
  double depth_fraction = 0;  // of the nucleus's thickness at the trench centre
  double length_mm = 0;       // 5th–95th percentile range along the axis, /0.9
  double volume_mm3 = 0;
  std::vector<uint32_t> strokes;
};

struct TrenchReport {
  std::vector<Trench> trenches;   // largest volume first
  double crossing_angle_deg = 0;  // between the two largest; 0 with fewer than two
  double volume_removed_mm3 = 0;
};

struct TrenchSettings {
  double same_direction_deg = 25;  // strokes within this angle ...
  double same_line_mm = 0.8;  // ... and this far apart (centre to the other's axis) are one trench
  double core_radius_mm = 1.0;  // depth is measured within this distance of the lens axis
  double min_stroke_volume_mm3 =
      0.01;  // strokes that removed less are ignored (touches, not trenches)
};

// Throws std::invalid_argument if the nucleus shape is not positive.
TrenchReport measure_trenches(std::span<const RemovedElement> removed, const NucleusShape& nucleus,
                              const TrenchSettings& settings = {});

// z of the nucleus's anterior / posterior surface above (x, y); NaN outside the nucleus.
double nucleus_anterior_z(const NucleusShape& n, double x, double y);
double nucleus_posterior_z(const NucleusShape& n, double x, double y);

}  // namespace phaco::lens
