#include "systems/grasp/grasp.hpp"

#include <limits>

namespace phaco::grasp {

uint32_t nearest_particle(const Particles& p, const Vec3& tip, double radius_mm,
                          ParticleKind kind) {
  uint32_t best = kInvalidIndex;
  double best_d2 = radius_mm * radius_mm;
  for (uint32_t i = 0; i < p.slots.size(); ++i) {
    if (!p.slots.alive(i) || p.kind[i] != kind) continue;
    const double dx = p.x[i] - tip.x(), dy = p.y[i] - tip.y(), dz = p.z[i] - tip.z();
    const double d2 = dx * dx + dy * dy + dz * dz;
    if (d2 <= best_d2 && (best == kInvalidIndex || d2 < best_d2)) {
      best = i;
      best_d2 = d2;
    }
  }
  return best;
}

GraspEvent update_grasp(GraspState& s, Particles& p, const Vec3& tip, double grip, double dt_s,
                        const GraspSettings& settings) {
  GraspEvent event;
  const bool was_closed = s.closed;
  if (!s.closed && grip >= settings.close_at) s.closed = true;
  if (s.closed && grip < settings.open_at) s.closed = false;

  if (s.closed && !was_closed) {
    s.particle = nearest_particle(p, tip, settings.radius_mm);
    if (s.holding()) {
      p.kind[s.particle] = ParticleKind::Scripted;
      event.grasped = true;
    } else {
      event.missed = true;
    }
  }
  if (s.holding() && !p.slots.alive(s.particle)) s.particle = kInvalidIndex;  // removed by a cut
  if (!s.holding()) return event;

  const uint32_t i = s.particle;
  const float inv_dt = dt_s > 0 ? static_cast<float>(1.0 / dt_s) : 0.0f;
  p.vx[i] = (static_cast<float>(tip.x()) - p.x[i]) * inv_dt;
  p.vy[i] = (static_cast<float>(tip.y()) - p.y[i]) * inv_dt;
  p.vz[i] = (static_cast<float>(tip.z()) - p.z[i]) * inv_dt;
  p.x[i] = static_cast<float>(tip.x());
  p.y[i] = static_cast<float>(tip.y());
  p.z[i] = static_cast<float>(tip.z());
  if (!s.closed) {
    p.kind[i] = ParticleKind::Free;  // keeps the tool's velocity as it lets go
    s.particle = kInvalidIndex;
    event.released = true;
  }
  return event;
}

}  // namespace phaco::grasp
