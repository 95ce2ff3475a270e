#include "systems/nucleus/rotation.hpp"

#include <algorithm>
#include <cassert>
#include <cmath>

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

double applied_torque(const Axis& axis, const Vec3& prev_contact, const Vec3& contact,
                      const RotationSettings& s) {
  const Vec3 force = s.force_per_mm * (contact - prev_contact);
  return (contact - axis.point).cross(force).dot(unit_direction(axis));
}

double angular_acceleration(double torque, double damping_torque, double inertia) {
  const double td = std::abs(damping_torque);
  if (!(inertia > 0) || !(std::abs(torque) > td)) return 0;
  return (torque - std::copysign(td, torque)) / inertia;
}

double rotation_step(NucleusRotation& state, double torque, const RotationSettings& s,
                     double dt_s) {
  const double alpha = angular_acceleration(torque, s.damping_torque, state.inertia);
  const double theta = 0.5 * alpha * dt_s * dt_s;
  state.angle_rad += theta;
  return theta;
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
