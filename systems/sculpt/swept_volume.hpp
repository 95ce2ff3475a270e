#pragma once
// Reference for sculpting accuracy: the exact volume of lens the tip sweeps along a path
// (issue 5: removed volume against the exact volume of the tip–lens intersection).
//
// The region is the union of the capsules of radius r around the segments of a polyline (the tip
// sphere swept along it), intersected with the lens: two half-ellipsoids x²+y² ≤ a²(1 − z²/c²),
// c = c_anterior above z = 0, c_posterior below (DESIGN.md §6).
//  - capsule_volume_mm3: a straight segment fully inside the lens, π r² L + 4/3 π r³.
//  - swept_volume_in_lens: a general polyline that may leave the lens. Each vertical line meets a
//    capsule in one interval (a capsule is convex), computed in closed form; intervals of the
//    segments are merged and clipped to the lens's z range on that line, so z is exact and only
//    the (x, y) integral is numerical (midpoint rule on square columns). It runs at column size h
//    and h/2, returns the h/2 value and |V(h) − V(h/2)| as its error estimate.
// Pure function; reads and writes nothing else.
#include <cstdint>
#include <span>

#include "engine/core/math.hpp"

namespace phaco::sculpt {

struct LensShape {
  double a = 4.7;            // equatorial semi-axis, mm
  double c_anterior = 1.8;   // anterior pole z, mm
  double c_posterior = 2.7;  // posterior pole at z = -c_posterior, mm
};

struct SweptVolume {
  double volume_mm3 = 0.0;  // at column size h/2
  double error_mm3 = 0.0;   // |V(h) - V(h/2)|
  uint64_t columns = 0;     // columns evaluated at h/2
};

inline double capsule_volume_mm3(double radius, double length) {
  constexpr double kPi = 3.14159265358979323846;
  return kPi * radius * radius * length + 4.0 / 3.0 * kPi * radius * radius * radius;
}

// Throws std::invalid_argument on an empty path, a negative radius or a non-positive column size.
SweptVolume swept_volume_in_lens(std::span<const Vec3> path, double radius, const LensShape& lens,
                                 double column_mm = 0.01);

}  // namespace phaco::sculpt
