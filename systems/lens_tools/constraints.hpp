#pragma once
// Environment constraints on the lens cells (seed 002 §6: "the cornea, the anterior camera and the
// posterior camera are geometrically modeled as half-spheres in order to compute simple
// point-sphere collisions and to constrain the cells positions"; §6.1: "inelastic collision").
//
//                 cornea (posterior surface: a ball the cells stay inside)
//               .-~~~~~~~~~-.
//             /   anterior    \         The capsular bag is the intersection of two balls: the
//            |  ___cap____     |        anterior cap's sphere (through the anterior pole) and the
//            |/    lens    \   |        posterior cap's (through the posterior pole), fitted to the
//       -----+--- equator --+--+---     lens as CapFit says. Each ball only bounds the bag on its
//            \____________/            own side of the rim where they meet, so together they are
//               posterior cap           the seed's two half-spheres.
//
// A cell outside is moved to the nearest point of the allowed set (exact Euclidean projection onto
// the intersection of two balls: onto one sphere, or onto their rim circle when neither single
// projection lies in the other ball), a hair inside so float rounding cannot leave it out. Its
// velocity loses the outward normal component (perfectly inelastic: no bounce), and its contact
// flag is set so shape matching can treat it as very heavy (§6.1: "the interacting cells are forced
// to assume a very big mass").
//
// With a rhexis (rhexis_radius_mm > 0) cells within that distance of the optical axis are not held
// by the anterior cap: they may leave the bag through the opening and are then bounded by the
// posterior cap and the cornea. The capsule has no thickness here, so a cell that left through the
// opening and drifts sideways beyond its radius is put back into the bag.
//
// Reads: cells (alive). Writes: cells (x, y, z, vx, vy, vz), contact flags.
#include <cstdint>
#include <span>

#include "components/lens_cells.hpp"
#include "engine/core/math.hpp"

namespace phaco::lens_tools {

struct Ball {
  Vec3 centre = Vec3::Zero();  // mm
  double radius_mm = 0;        // ≤ 0: absent (no constraint)
};

struct EyeBounds {
  Ball cornea;                  // posterior corneal surface
  Ball anterior_capsule;        // sphere of the anterior cap
  Ball posterior_capsule;       // sphere of the posterior cap
  double rhexis_radius_mm = 0;  // 0: closed bag
};

// How a cap's sphere is fitted to the half-ellipsoid of the lens (equator radius a, pole height c):
//   ThroughEquator  through the pole and the equator circle, R = (a² + c²) / 2c. Tight at both, but
//                   an oblate lens is flatter than the sphere near the pole, so its shoulders stick
//                   out (standard eye: by up to 0.33 mm on either side) and a lens at rest is in
//                   contact there.
//   ContainsLens    the smallest sphere through the pole that holds the whole half-ellipsoid,
//                   R = max(a², (a² + c²)/2) / c (for an oblate lens the pole's radius of curvature
//                   a²/c). A lens at rest touches only at the poles; the price is slack at the
//                   equator (standard eye: the bag's rim at r ≈ 6.2 instead of 4.7).
enum class CapFit : uint8_t { ContainsLens, ThroughEquator };

// The cap sphere for a pole on the optical axis at height pole_z (sign: which cap) over the equator
// circle of the given radius in the plane z = 0 (the lens's equatorial plane, DESIGN.md §6).
Ball cap_sphere(double equator_radius_mm, double pole_z_mm, CapFit fit = CapFit::ContainsLens);

// Bounds of the standard geometry: lens equator radius, anterior and posterior pole heights,
// posterior corneal apex height and radius (sphere centred on the axis below the apex).
EyeBounds eye_bounds(double equator_radius_mm, double anterior_pole_z_mm,
                     double posterior_pole_z_mm, double cornea_posterior_apex_z_mm,
                     double cornea_posterior_radius_mm, double rhexis_radius_mm = 0,
                     CapFit fit = CapFit::ContainsLens);

// Nearest point of ball A ∩ ball B to p (either ball may be absent). Returns p when p is inside.
// `skin_mm` pulls a projected point that far inside.
Vec3 project_into(const Vec3& p, const Ball& a, const Ball& b, double skin_mm);

// Is p inside the set constrain() enforces (cell at radius r from the optical axis)?
bool inside_bounds(const Vec3& p, const EyeBounds& bounds, double tolerance_mm);

// A float pre-test for inside_bounds(p, bounds, tolerance_mm): true only where that is surely
// true (each ball taken 1e-4 mm smaller than the exact test's, far above float rounding at eye
// scale), so a caller that asks inside_bounds only where this says false decides every point as
// inside_bounds alone would.
struct SurelyInside {
  SurelyInside(const EyeBounds& bounds, double tolerance_mm);
  bool operator()(float x, float y, float z) const {
    const bool open = open2 >= 0 && x * x + y * y < open2;
    return (open || in(anterior, x, y, z)) && in(posterior, x, y, z) && in(cornea, x, y, z);
  }

  struct FloatBall {
    float cx = 0, cy = 0, cz = 0, r2 = 0;
    bool present = false;
  };
  static bool in(const FloatBall& b, float x, float y, float z) {
    const float dx = x - b.cx, dy = y - b.cy, dz = z - b.cz;
    return !b.present || dx * dx + dy * dy + dz * dz <= b.r2;
  }
  FloatBall cornea, anterior, posterior;
  float open2 = -1;  // (rhexis radius − margin)², < 0 without an opening
};

// Projects every alive cell into the bounds and removes the outward velocity of moved cells.
// `contact` (empty, or one entry per cell) is set to 1 for moved cells and 0 for the others.
void constrain(const CellSpans& cells, const EyeBounds& bounds, std::span<uint8_t> contact);

}  // namespace phaco::lens_tools
