#include "systems/nucleus/rotation.hpp"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <numbers>

#include "engine/core/invariants.hpp"
#include "engine/schedule/parallel.hpp"

namespace phaco::nucleus {

namespace {

constexpr uint32_t kGrain = 4096;

Vec3 unit_direction(const Axis& axis) {
  const double len = axis.direction.norm();
  return len > 0 ? Vec3(axis.direction / len) : Vec3(Vec3::UnitZ());
}

double sum_r2(std::span<const Vec3> centres, const Axis& axis) {
  const Axis unit{axis.point, unit_direction(axis)};
  return parallel_reduce_ordered(
      0, static_cast<uint32_t>(centres.size()), kGrain, 0.0,
      [&](uint32_t b, uint32_t e) {
        double s = 0;
        for (uint32_t i = b; i < e; ++i) s += axis_distance2(centres[i], unit);
        return s;
      },
      [](double l, double r) { return l + r; });
}

}  // namespace

double axis_distance2(const Vec3& p, const Axis& axis) {
  const Vec3 d = p - axis.point;
  const double along = d.dot(axis.direction);
  return std::max(d.squaredNorm() - along * along, 0.0);
}

NucleusRotation make_rotation(std::span<const Vec3> centres, double tet_mass_kg, const Axis& axis) {
  NucleusRotation s;
  s.axis = {axis.point, unit_direction(axis)};
  s.tet_mass_kg = tet_mass_kg;
  s.inertia0 = tet_mass_kg * sum_r2(centres, s.axis);
  s.inertia = s.inertia0;
  return s;
}

void remove_tets(NucleusRotation& state, std::span<const Vec3> removed_centres) {
  state.removed_sum_r2 += sum_r2(removed_centres, state.axis);
  state.inertia = std::max(state.inertia0 - state.tet_mass_kg * state.removed_sum_r2, 0.0);
}

double free_rotation_step(NucleusRotation& state, const RotationSettings& s, double dt_s) {
  if (!(state.inertia > 0)) {
    state.angular_velocity = 0;
    return 0;
  }
  // Viscous damping implicitly (stable for any c Δt / I), then Coulomb friction that may stop
  // the nucleus but never turn it back.
  double w = state.angular_velocity / (1.0 + s.damping * dt_s / state.inertia);
  const double stop = s.friction_torque * dt_s / state.inertia;
  w = std::abs(w) <= stop ? 0.0 : w - std::copysign(stop, w);
  state.angular_velocity = w;
  const double theta = w * dt_s;
  state.angle_rad += theta;
  return theta;
}

double wall_clearance_angle(std::span<const Vec3> wall_points, const Vec3& tip, double radius,
                            int sign) {
  const double rho_t = std::hypot(tip.x(), tip.y());
  if (!(rho_t > 0) || sign == 0) return 0;
  const double phi_t = std::atan2(tip.y(), tip.x());
  const double s = sign > 0 ? 1.0 : -1.0;
  double need = 0;
  for (const Vec3& p : wall_points) {
    const double rho = std::hypot(p.x(), p.y());
    if (!(rho > 0)) continue;
    const double dz = p.z() - tip.z();
    // The point's circle about the axis is inside the sphere for |ψ| < ψmax (law of cosines).
    const double c = (rho_t * rho_t + rho * rho + dz * dz - radius * radius) / (2 * rho_t * rho);
    if (c >= 1) continue;  // the circle misses the sphere
    const double psi_max = std::acos(std::max(c, -1.0));
    const double psi = std::remainder(std::atan2(p.y(), p.x()) - phi_t, 2 * std::numbers::pi) * s;
    if (!(psi > 0)) continue;  // behind the tip: the tip moves away from it
    need = std::max(need, psi_max - psi);
  }
  return need;
}

double contact_rotation_step(NucleusRotation& state, double clearance_rad, int sign, double dt_s) {
  if (!(clearance_rad > 0) || sign == 0 || !(state.inertia > 0) || !(dt_s > 0)) return 0;
  const double turn = sign > 0 ? clearance_rad : -clearance_rad;
  state.angle_rad += turn;
  state.angular_velocity += turn / dt_s;
  const double torque = state.inertia * clearance_rad / (dt_s * dt_s);
  state.contact_torque_max = std::max(state.contact_torque_max, torque);
  return torque;
}

void rotate_about_axis(std::span<float> x, std::span<float> y, std::span<float> z, const Axis& axis,
                       double theta_rad) {
  assert(same_size(x, y, z));
  if (theta_rad == 0) return;
  const Eigen::Matrix3d r = Eigen::AngleAxisd(theta_rad, unit_direction(axis)).toRotationMatrix();
  const Vec3 o = axis.point;
  parallel_for(0, static_cast<uint32_t>(x.size()), kGrain, [&](uint32_t b, uint32_t e, int) {
    for (uint32_t i = b; i < e; ++i) {
      const Vec3 q = o + r * (Vec3(x[i], y[i], z[i]) - o);
      x[i] = static_cast<float>(q.x());
      y[i] = static_cast<float>(q.y());
      z[i] = static_cast<float>(q.z());
    }
  });
}

void rotate_about_axis(std::span<Vec3> points, const Axis& axis, double theta_rad) {
  if (theta_rad == 0) return;
  const Eigen::Matrix3d r = Eigen::AngleAxisd(theta_rad, unit_direction(axis)).toRotationMatrix();
  const Vec3 o = axis.point;
  parallel_for(0, static_cast<uint32_t>(points.size()), kGrain, [&](uint32_t b, uint32_t e, int) {
    for (uint32_t i = b; i < e; ++i) points[i] = o + r * (points[i] - o);
  });
}

}  // namespace phaco::nucleus
