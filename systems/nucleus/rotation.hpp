#pragma once
// Nucleus rotation about the optical axis during phaco-sculpting (seed 000 §5.4, its inertia; the
// push as a kinematic contact, issue 19).
//
//   moment of inertia, every tet a point mass m at its centre, R_i its distance from the axis:
//       I0 = m Σ_i R_i²            and, after removing tets j,   I = I0 − m Σ_j r_j²
//
// Why not the seed's push law (θ = ½·α·Δt² from a force linear in the contact point's travel,
// no angular velocity): it turns the nucleus by whatever the tip's travel happens to be in the
// frames the tip "touches" a tet, so the same push turns a nucleus differently at each mesh
// level (75-99.5 deg for one quarter-turn push at levels 0-4 once the trench is open), and it
// scales with Δt³. A nucleus is a rigid body in the capsular bag; the tip in a trench cannot pass
// its wall. So:
//
//   the bag (zonules, cortex, viscoelastic) resists with Coulomb friction T_f (the seed's
//   constant damping torque T_d) and viscous damping c:
//       I dω/dt = T_c − c ω − T_f sign(ω)
//   T_c ≥ 0 is the contact torque of the tip on the trench wall ahead of it: whatever keeps the
//   wall from passing the tip (a unilateral constraint), never more than moves the wall with the
//   tip (the tip cannot throw the nucleus).
//
//   one step (Moreau time stepping, position level, as position-based dynamics):
//     1. free:    ω⁻ = ω / (1 + c Δt / I), then |ω⁻| less T_f Δt / I, not past zero (stick)
//                 θ⁻ = θ + ω⁻ Δt
//     2. contact: the caller finds, at θ⁻, the least turn Δ ≥ 0 in the push direction that
//                 takes every wall point out of the tip's sphere (wall_clearance_angle), capped
//                 at the tip's own angular travel relative to the nucleus;
//                 θ = θ⁻ + s Δ,  ω = ω⁻ + s Δ / Δt,  T_c = I Δ / Δt² (the wall's impulse per step)
//
// With c Δt / I ≫ 1 (the standard eye: viscoelastic in the bag, docs/lens.md) the nucleus stops
// within a step of the tip stopping: the seed's quasi-static assumption holds, but the angle is
// the tip's geometry, not the mesh's: the same push turns the nucleus by the tip's travel less
// the trench's free play at every level.
//
// Units: mass kg, lengths mm, so I is kg·mm², torque mN·mm (= kg·mm²/s²), c mN·mm·s/rad.
// The sums are in double, in index order (deterministic); I never goes below zero.
//
// Reads: tet (or cell) centres, the probe's tip. Writes: NucleusRotation, and the positions
// passed to rotate_about_axis.
#include <cstdint>
#include <span>

#include "engine/core/math.hpp"

namespace phaco::nucleus {

struct Axis {
  Vec3 point = Vec3::Zero();       // mm, a point on the axis
  Vec3 direction = Vec3::UnitZ();  // unit; the optical axis, +z toward the surgeon
};

struct RotationSettings {
  double friction_torque = 0.05;  // T_f, Coulomb friction of the bag, mN·mm (the seed's T_d)
  double damping = 20.0;          // c, viscous damping of the bag, mN·mm·s/rad
};

struct NucleusRotation {
  Axis axis;
  double tet_mass_kg = 0;         // m, equal for every tet
  double inertia0 = 0;            // I0, kg·mm²
  double removed_sum_r2 = 0;      // Σ_j r_j² over removed tets, mm²
  double inertia = 0;             // I = I0 − m Σ_j r_j², kg·mm²
  double angle_rad = 0;           // accumulated rotation, counter-clockwise about axis.direction
  double angular_velocity = 0;    // ω, rad/s
  double contact_torque_max = 0;  // largest T_c so far, mN·mm
};

// Squared distance of p from the axis.
double axis_distance2(const Vec3& p, const Axis& axis);

// I0 from the tet centres (every tet of mass m).
NucleusRotation make_rotation(std::span<const Vec3> centres, double tet_mass_kg,
                              const Axis& axis = {});

// Removes tets whose centres are given: I −= m Σ r_j² (clamped at zero).
void remove_tets(NucleusRotation& state, std::span<const Vec3> removed_centres);

// Step 1: the bag's friction and damping on ω (implicit in c, Coulomb stick), then θ += ω Δt.
// Returns the turn ω Δt. A nucleus with no inertia left does not move.
double free_rotation_step(NucleusRotation& state, const RotationSettings& s, double dt_s);

// Step 2: the least turn Δ ≥ 0 in direction `sign` (+1 counter-clockwise about the axis, −1
// clockwise) that takes every wall point out of the sphere (tip, radius): each point ahead of the
// tip (angle from the tip's half-plane in (0, π) in that direction) must end at least the angle
// at which its circle about the axis leaves the sphere. Points behind the tip, or whose circle
// misses the sphere, ask nothing. Points and tip in one frame, the axis through the origin along
// +z (the lens frame).
double wall_clearance_angle(std::span<const Vec3> wall_points, const Vec3& tip, double radius,
                            int sign);

// Step 2, applied: turns by sign·Δ, adds sign·Δ/Δt to ω, records T_c = I Δ / Δt². Returns T_c.
double contact_rotation_step(NucleusRotation& state, double clearance_rad, int sign, double dt_s);

// Rotates points about the axis by θ (right-handed about axis.direction), in place; distances to
// the axis are kept. Float SoA (cells) and double points (tet-mesh vertices).
void rotate_about_axis(std::span<float> x, std::span<float> y, std::span<float> z, const Axis& axis,
                       double theta_rad);
void rotate_about_axis(std::span<Vec3> points, const Axis& axis, double theta_rad);

}  // namespace phaco::nucleus
