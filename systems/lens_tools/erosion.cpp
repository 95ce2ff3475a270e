#include "systems/lens_tools/erosion.hpp"

#include <algorithm>
#include <cassert>
#include <cmath>

#include "engine/core/invariants.hpp"
#include "systems/lens_tools/collect_ids.hpp"

namespace phaco::lens_tools {

namespace {

// The cone in float, normalised once per call.
struct Cone {
  Vec3f apex, axis;
  float reach, reach2, half_angle, cos_half;
  float scale;  // k · power · dt
};

Cone make_cone(const PhacoTip& tip, const ErosionSettings& s, double dt_s) {
  Cone c;
  c.apex = tip.apex.cast<float>();
  const double len = tip.axis.norm();
  c.axis = (len > 0 ? Vec3(tip.axis / len) : Vec3(-Vec3::UnitZ())).cast<float>();
  c.reach = static_cast<float>(std::max(s.reach_mm, 0.0));
  c.reach2 = c.reach * c.reach;
  c.half_angle = static_cast<float>(std::clamp(s.half_angle_rad, 0.0, M_PI));
  c.cos_half = std::cos(c.half_angle);
  c.scale = static_cast<float>(std::max(s.rate_per_s * tip.power * dt_s, 0.0));
  return c;
}

inline float probability(const Cone& c, float px, float py, float pz, float hardness) {
  const float dx = px - c.apex.x(), dy = py - c.apex.y(), dz = pz - c.apex.z();
  const float d2 = dx * dx + dy * dy + dz * dz;
  if (!(d2 <= c.reach2) || c.reach <= 0) return 0.0f;
  const float d = std::sqrt(d2);
  float theta = 0.0f;
  if (d > 0.0f) {
    const float cos_t = (dx * c.axis.x() + dy * c.axis.y() + dz * c.axis.z()) / d;
    if (cos_t < c.cos_half) return 0.0f;
    theta = std::acos(std::clamp(cos_t, -1.0f, 1.0f));
  }
  const float w_d = 1.0f - d / c.reach;
  const float w_t = c.half_angle > 0 ? std::max(1.0f - theta / c.half_angle, 0.0f) : 0.0f;
  const float soft = 1.0f - std::clamp(hardness, 0.0f, 1.0f);
  return std::clamp(c.scale * soft * w_d * w_t, 0.0f, 1.0f);
}

}  // namespace

PhacoTip phaco_tip(const ToolPose& pose, double power_setting) {
  PhacoTip tip;
  tip.apex = pose.pos;
  tip.axis = pose.quat.normalized() * Vec3(0, 0, -1);
  tip.power = ultrasound_power(pose.pedal, power_setting);
  return tip;
}

double erosion_weight(double distance_mm, double angle_rad, const ErosionSettings& s) {
  if (s.reach_mm <= 0 || s.half_angle_rad <= 0) return 0;
  if (distance_mm > s.reach_mm || angle_rad > s.half_angle_rad) return 0;
  return (1.0 - distance_mm / s.reach_mm) * (1.0 - angle_rad / s.half_angle_rad);
}

float removal_probability(const Vec3f& cell, float hardness, const PhacoTip& tip,
                          const ErosionSettings& s, double dt_s) {
  return probability(make_cone(tip, s, dt_s), cell.x(), cell.y(), cell.z(), hardness);
}

void erode(const CellSpans& cells, const PhacoTip& tip, const ErosionSettings& s,
           const CounterRng& rng, uint64_t frame, double dt_s, ErosionScratch& scratch,
           std::vector<uint32_t>& removed) {
  assert(cells.in_step());
  const Cone cone = make_cone(tip, s, dt_s);
  if (cone.scale <= 0.0f) {  // pedal below 3, or no time: nothing to draw
    removed.clear();
    return;
  }
  const float* x = cells.x.data();
  const float* y = cells.y.data();
  const float* z = cells.z.data();
  const uint8_t* alive = cells.alive.data();
  const float* hard = cells.hardness.data();
  detail::collect_ids(cells.size(), scratch.ids, scratch.counts, removed, [&](uint32_t i) {
    if (!alive[i]) return false;
    const float p = probability(cone, x[i], y[i], z[i], hard[i]);
    return p > 0.0f && rng.uniform(frame, i) < p;
  });
}

}  // namespace phaco::lens_tools
