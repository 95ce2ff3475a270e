// Backtracking on backward Euler's incremental potential, shared by implicit Euler and the
// predictor; see implicit.hpp for Φ and why the step needs it.
#include <cmath>

#include "engine/schedule/parallel.hpp"
#include "systems/deform/implicit.hpp"

namespace phaco::deform::implicit_detail {

namespace {

// From this many unknowns the line search's first two evaluations run side by side (a task costs
// a few microseconds; one evaluation over 256 unknowns and their springs costs about ten).
constexpr size_t kParallelPotentialUnknowns = 256;

// Φ(x_n + α·Δx) over the unknowns and `springs`; the terms the step cannot change are left out.
double incremental_potential(const Membrane& m, double dt, std::span<const uint32_t> unknowns,
                             std::span<const uint32_t> unknown_of,
                             std::span<const uint32_t> springs, const double* step_dx,
                             double alpha) {
  const Particles& p = m.particles;
  const Springs& s = m.springs;
  const Dynamics& dyn = m.dynamics;
  const double drag = double(dyn.damping_per_s) + dyn.viscosity_per_s;
  const bool glued = m.glue && m.glue->x.size() == p.slots.size();
  const double glue_k = glued ? dyn.glue_stiffness_mn_mm : 0.0;
  auto coord = [&](uint32_t i, int a) -> double {
    return a == 0 ? p.x[i] : a == 1 ? p.y[i] : p.z[i];
  };
  auto at = [&](uint32_t i, int a) {
    const uint32_t u = unknown_of[i];
    return u == kNotUnknown ? coord(i, a) : coord(i, a) + alpha * step_dx[3 * u + a];
  };
  double phi = 0.0;
  for (size_t u = 0; u < unknowns.size(); ++u) {
    const uint32_t i = unknowns[u];
    const double true_mass = 1.0 / p.inv_mass[i];
    const double mass = mass_scale(dyn) * true_mass;
    const double v[3] = {p.vx[i], p.vy[i], p.vz[i]};
    for (int a = 0; a < 3; ++a) {
      const double dx = alpha * step_dx[3 * u + a], x = coord(i, a) + dx;
      const double inertial = dx - dt * v[a];
      const double rest = glued ? (a == 0   ? m.glue->x[i]
                                   : a == 1 ? m.glue->y[i]
                                            : m.glue->z[i])
                                : x;
      phi += mass / (2.0 * dt * dt) * inertial * inertial + mass * drag / (2.0 * dt) * dx * dx +
             0.5 * glue_k * (x - rest) * (x - rest) - true_mass * dyn.gravity_mm_s2[a] * x;
    }
  }
  for (const PointLoad& load : m.loads) {  // a constant force's potential is −F·x
    if (load.particle >= unknown_of.size() || unknown_of[load.particle] == kNotUnknown) continue;
    if (!std::isfinite(load.fx) || !std::isfinite(load.fy) || !std::isfinite(load.fz)) continue;
    phi -= load.fx * at(load.particle, 0) + load.fy * at(load.particle, 1) +
           load.fz * at(load.particle, 2);
  }
  for (uint32_t e : springs) {
    const uint32_t i = s.i[e], j = s.j[e];
    const double dx = at(j, 0) - at(i, 0), dy = at(j, 1) - at(i, 1), dz = at(j, 2) - at(i, 2);
    const double ext = std::sqrt(dx * dx + dy * dy + dz * dz) - s.rest_length[e];
    phi += dyn.law == SpringLaw::Linear ? 0.5 * s.stiffness[e] * ext * ext
                                        : s.stiffness[e] * std::fabs(ext) * ext * ext / 3.0;
  }
  return phi;
}

}  // namespace

void add_point_loads(const Membrane& m, std::span<const uint32_t> unknown_of, double* force) {
  for (const PointLoad& load : m.loads) {
    if (load.particle >= unknown_of.size() || unknown_of[load.particle] == kNotUnknown) continue;
    // Non-finite loads are rejected (and counted) by the guard's force pass; skip them here too.
    if (!std::isfinite(load.fx) || !std::isfinite(load.fy) || !std::isfinite(load.fz)) continue;
    const uint32_t u = unknown_of[load.particle];
    force[3 * u + 0] += load.fx;
    force[3 * u + 1] += load.fy;
    force[3 * u + 2] += load.fz;
  }
}

double line_search(const Membrane& m, double dt, int max_halvings,
                   std::span<const uint32_t> unknowns, std::span<const uint32_t> unknown_of,
                   std::span<const uint32_t> springs, const double* step_dx) {
  // Φ at the start and at the full step are independent: on a large set, two threads evaluate
  // them side by side (each sum unchanged, so the same bits). Most steps stop at α = 1.
  const auto phi = [&](double a) {
    return incremental_potential(m, dt, unknowns, unknown_of, springs, step_dx, a);
  };
  double phi0 = 0.0, phi_full = 0.0;
  if (unknowns.size() >= kParallelPotentialUnknowns && max_halvings > 0)
    parallel_invoke([&] { phi0 = phi(0.0); }, [&] { phi_full = phi(1.0); });
  else
    phi0 = phi(0.0), phi_full = max_halvings > 0 ? phi(1.0) : 0.0;
  double alpha = 1.0;
  for (int h = 0; h < max_halvings; ++h, alpha *= 0.5)
    if ((h == 0 ? phi_full : phi(alpha)) <= phi0 + 1e-12 * std::fabs(phi0)) break;
  return alpha;
}

}  // namespace phaco::deform::implicit_detail
