#include "systems/lens_tools/fluidics.hpp"

#include <algorithm>
#include <cassert>
#include <cmath>

#include "engine/core/invariants.hpp"
#include "engine/schedule/parallel.hpp"

namespace phaco::lens_tools {

namespace {
constexpr double kSecondsPerMinute = 60.0;
constexpr uint32_t kPortGrain = 8192;  // cells per chunk of the port scan
}  // namespace

double vacuum_rise_time_s(const FluidicsSettings& s) {
  const double flow_ml_s = std::max(s.flow_ml_min, 1e-6) / kSecondsPerMinute;
  return s.compliance_ml_per_mmhg * s.vacuum_limit_mmhg / flow_ml_s;
}

double step_vacuum(double vacuum_mmhg, bool aspirating, bool occluded, const FluidicsSettings& s,
                   double dt_s) {
  const double target =
      !aspirating ? 0.0
      : occluded  ? s.vacuum_limit_mmhg
                 : std::min(s.vacuum_limit_mmhg, s.open_resistance_mmhg_per_ml_min * s.flow_ml_min);
  const double tau = std::max(vacuum_rise_time_s(s), 1e-6);
  return target + (vacuum_mmhg - target) * std::exp(-dt_s / tau);
}

double holding_force_mn(double vacuum_mmhg, const FluidicsSettings& s) {
  return vacuum_mmhg * kKpaPerMmhg * M_PI * s.port_radius_mm * s.port_radius_mm;
}

PortCover port_cover(const CellSpans& cells, std::span<const float> volume,
                     std::span<const uint32_t> label, uint32_t fragments, const Vec3& port,
                     const FluidicsSettings& s, std::vector<double>& per_fragment) {
  assert(cells.in_step() && same_size(cells.x, volume, label));
  PortCover out;
  if (per_fragment.size() < fragments) per_fragment.resize(fragments);
  std::fill(per_fragment.begin(), per_fragment.begin() + fragments, 0.0);
  const Vec3f p = port.cast<float>();
  const float r2 = static_cast<float>(s.port_radius_mm * s.port_radius_mm);
  // The cells in the port (few), found in parallel over fixed chunks and listed in id order, then
  // summed in that order: the same sums as one walk.
  const std::vector<uint32_t> in_port = parallel_reduce_ordered(
      0u, cells.size(), kPortGrain, std::vector<uint32_t>{},
      [&](uint32_t b, uint32_t e) {
        std::vector<uint32_t> ids;
        for (uint32_t i = b; i < e; ++i) {
          if (!cells.alive[i] || label[i] >= fragments) continue;
          if ((Vec3f(cells.x[i], cells.y[i], cells.z[i]) - p).squaredNorm() > r2) continue;
          ids.push_back(i);
        }
        return ids;
      },
      [](std::vector<uint32_t> a, const std::vector<uint32_t>& b) {
        a.insert(a.end(), b.begin(), b.end());
        return a;
      });
  for (const uint32_t i : in_port) per_fragment[label[i]] += volume[i];
  double best = 0;
  for (uint32_t f = 0; f < fragments; ++f)
    if (per_fragment[f] > best) best = per_fragment[f], out.fragment = f;
  if (out.fragment == 0xffffffffu) return out;
  const double sphere = 4.0 / 3.0 * M_PI * std::pow(s.port_radius_mm, 3);
  out.fraction = best / sphere;
  out.occluded = out.fraction >= s.occlusion_fraction;
  return out;
}

void draw_to_tip(const CellSpans& cells, std::span<const uint32_t> members, const Vec3& port,
                 const Vec3& tip_velocity, const Vec3& nearest, const FluidicsSettings& s,
                 double dt_s) {
  assert(cells.in_step() && all_below(members, cells.size()));
  const Vec3 to_port = port - nearest;
  const double d = to_port.norm();
  Vec3 target = tip_velocity;
  if (d > 0) target += to_port / d * std::min(d / std::max(s.draw_time_s, 1e-6), s.feed_speed_mm_s);
  const float beta = static_cast<float>(1.0 - std::exp(-s.draw_rate_per_s * dt_s));
  const Vec3f t = target.cast<float>();
  const float dt = static_cast<float>(dt_s);
  for (const uint32_t i : members) {
    if (!cells.alive[i]) continue;
    const Vec3f dv = beta * (t - Vec3f(cells.vx[i], cells.vy[i], cells.vz[i]));
    cells.vx[i] += dv.x(), cells.vy[i] += dv.y(), cells.vz[i] += dv.z();
    cells.x[i] += dv.x() * dt, cells.y[i] += dv.y() * dt, cells.z[i] += dv.z() * dt;
  }
}

}  // namespace phaco::lens_tools
