#pragma once
// Nucleus rotation about the optical axis during phaco-sculpting (seed 000 §5.4).
//
//   moment of inertia, every tet a point mass m at its centre, R_i its distance from the axis:
//       I0 = m Σ_i R_i²            and, after removing tets j,   I = I0 − m Σ_j r_j²
//   applied torque from the probe: the force is linear in the distance between consecutive
//   lens–probe contact points, along the probe's motion, F = k (c_now − c_prev); T = ((c_now − o)
//   × F) · a about the axis (point o, unit direction a)
//   constant damping torque T_d opposing T; the lens turns only when |T| > T_d:
//       α = (T − sign(T) T_d) / I,      else α = 0
//   quasi-static (no angular velocity carried from step to step, as the seed assumes):
//       θ = ½ α Δt²
//
// Units: mass kg, lengths mm, so I is kg·mm², torque mN·mm (= kg·mm²/s²), α rad/s².
// The sums are in double, in index order (deterministic); I never goes below zero.
//
// Reads: tet (or cell) centres, the probe's contact points. Writes: NucleusRotation, and the
// positions passed to rotate_about_axis.
#include <cstdint>
#include <span>

#include "engine/core/math.hpp"

namespace phaco::nucleus {

struct Axis {
  Vec3 point = Vec3::Zero();       // mm, a point on the axis
  Vec3 direction = Vec3::UnitZ();  // unit; the optical axis, +z toward the surgeon
};

struct RotationSettings {
  double damping_torque = 0.05;  // T_d, mN·mm
  double force_per_mm = 2.0;     // k: applied force per mm of contact-point travel, mN/mm
};

struct NucleusRotation {
  Axis axis;
  double tet_mass_kg = 0;     // m, equal for every tet
  double inertia0 = 0;        // I0, kg·mm²
  double removed_sum_r2 = 0;  // Σ_j r_j² over removed tets, mm²
  double inertia = 0;         // I = I0 − m Σ_j r_j², kg·mm²
  double angle_rad = 0;       // accumulated rotation, counter-clockwise about axis.direction
};

// Squared distance of p from the axis.
double axis_distance2(const Vec3& p, const Axis& axis);

// I0 from the tet centres (every tet of mass m).
NucleusRotation make_rotation(std::span<const Vec3> centres, double tet_mass_kg,
                              const Axis& axis = {});

// Removes tets whose centres are given: I −= m Σ r_j² (clamped at zero).
void remove_tets(NucleusRotation& state, std::span<const Vec3> removed_centres);

// T about the axis from the probe's previous and current contact points (mN·mm).
double applied_torque(const Axis& axis, const Vec3& prev_contact, const Vec3& contact,
                      const RotationSettings& s);

// α from T, T_d and I (0 when |T| ≤ T_d or I ≤ 0), rad/s².
double angular_acceleration(double torque, double damping_torque, double inertia);

// θ = ½ α Δt² for this step; adds it to state.angle_rad and returns it.
double rotation_step(NucleusRotation& state, double torque, const RotationSettings& s, double dt_s);

// Rotates points about the axis by θ (right-handed about axis.direction), in place; distances to
// the axis are kept. Float SoA (cells) and double points (tet-mesh vertices).
void rotate_about_axis(std::span<float> x, std::span<float> y, std::span<float> z, const Axis& axis,
                       double theta_rad);
void rotate_about_axis(std::span<Vec3> points, const Axis& axis, double theta_rad);

}  // namespace phaco::nucleus
