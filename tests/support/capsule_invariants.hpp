#pragma once
// Test support: the bounds the scene's cut capsule is checked at (systems/topology_check), in the
// two shapes it has, and the capsule's rest shape as a particle table to check.
//
// The scene cuts and tears in the rest shape (procedures/scene/capsule_cutting.hpp), so that is
// where the cut's promise holds: no split below CutSettings::min_angle_deg (5°), a finish no
// lower than 1°; the invariants' defaults (area >= 1e-8 mm², angles >= 1°) apply there.
//
// The deformed shape is the cut's output pulled by the forceps and the tear, and the angle bound
// of the rest shape does not hold there, nor should it: the flap strip between the forceps and the
// tear's tip is stretched along the pull, and the fresh lip triangles there become needles
// (test_scene_cut_fuzz's 24 drills: smallest angle 0.0015°, smallest area 3.5e-7 mm²; the demo
// at level 3: 0.24°), while the same triangles in the rest shape keep >= 1°. The bounds below keep
// what float arithmetic needs of a triangle (the renderer's normals, contact, the tear direction):
// sin(1e-4°) = 1.7e-6, about 15 float epsilons, below which the normal is rounding noise; and a
// non-zero area, at the invariants' 1e-8 mm². They are not invariants of the physics: the flap
// folds, and a fold passes a triangle through zero area. A 200-drill search (seeds 1800-1999)
// found seed 1980 (level 0) with a triangle of rest area 2.8e-4 mm² next to the held forceps,
// stretched about 5x and turned over, sampled at 1.2e-4° and 3e-8 mm²: just above the bounds.
// So a failure of these bounds on a new seed or after a physics change is a fold to look at (is
// it physical?), not necessarily a cut bug; the rest-shape bounds are the cut's.
#include <gtest/gtest.h>

#include "components/particles.hpp"
#include "components/springs.hpp"
#include "components/triangles.hpp"
#include "procedures/scene/capsule_cutting.hpp"
#include "systems/topology_check/topology_check.hpp"

namespace phaco::test {

inline constexpr topology_check::InvariantThresholds kCapsuleRestBounds{};
inline constexpr topology_check::InvariantThresholds kCapsuleDeformedBounds{.min_area_mm2 = 1e-8,
                                                                            .min_angle_deg = 1e-4};

// The capsule's particles with the rest shape (CapsuleCutting::rest_x/y/z) as their positions.
inline Particles capsule_rest_shape(const Particles& p, const CapsuleCutting& cc) {
  Particles rest = p;
  rest.x = cc.rest_x, rest.y = cc.rest_y, rest.z = cc.rest_z;
  return rest;
}

// Every invariant on the deformed capsule at kCapsuleDeformedBounds and on its rest shape at
// kCapsuleRestBounds.
inline ::testing::AssertionResult capsule_sound(const Particles& p, const Triangles& tr,
                                                const Springs& springs, const CapsuleCutting& cc) {
  const auto deformed = topology_check::check_membrane(p, tr, springs, kCapsuleDeformedBounds);
  if (!deformed.ok()) return ::testing::AssertionFailure() << "deformed: " << deformed.summary();
  const auto rest =
      topology_check::check_membrane(capsule_rest_shape(p, cc), tr, springs, kCapsuleRestBounds);
  if (!rest.ok()) return ::testing::AssertionFailure() << "rest shape: " << rest.summary();
  return ::testing::AssertionSuccess();
}

}  // namespace phaco::test
