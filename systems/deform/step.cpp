#include <algorithm>
#include <cmath>

#include "systems/deform/deform.hpp"
#include "systems/deform/particle_set.hpp"

namespace phaco::deform {

Motion observe_motion(const Membrane& m) {
  const Particles& p = m.particles;
  const float limit2 = speed_limit2(m);
  const float inv_scale = inverse_mass_scale(m.dynamics);
  return for_each_in_play(particles_in_play(m), [&](uint32_t i, ChunkMotion& local) {
    observe(local, integrating_inv_mass(p, i, inv_scale) > 0.0f, p.x[i], p.y[i], p.z[i], p.vx[i],
            p.vy[i], p.vz[i], limit2);
  });
}

Motion integrate_once(Membrane& m, double dt_s, Integrator integrator, DeformState& st) {
  switch (integrator) {
    case Integrator::ExplicitEuler:
      return explicit_euler_step(m, dt_s);
    case Integrator::SymplecticEuler:
      return symplectic_euler_step(m, dt_s);
    case Integrator::SemiImplicit001:
      return semi_implicit_001_step(m, dt_s, st.axial_stiffness);
    case Integrator::Xpbd:
      return xpbd_step(m, dt_s, st.xpbd);
    case Integrator::ImplicitEuler:
      implicit_euler_step(m, dt_s, st.implicit);
      return observe_motion(m);
    case Integrator::ImplicitPredictor:
      implicit_predictor_step(m, dt_s, st.implicit);
      return observe_motion(m);
  }
  return observe_motion(m);
}

namespace {

uint32_t count_rejected_loads(const Membrane& m) {
  uint32_t rejected = 0;
  for (const PointLoad& load : m.loads) {
    const bool ok = load.particle < m.particles.slots.size() && std::isfinite(load.fx) &&
                    std::isfinite(load.fy) && std::isfinite(load.fz);
    rejected += ok ? 0 : 1;
  }
  return rejected;
}

// Runs the substeps of one attempt; false as soon as a substep leaves a bad particle.
bool run_attempt(Membrane& m, double dt_s, Integrator integrator, uint16_t substeps,
                 DeformState& st, StepReport& report) {
  const double h = dt_s / substeps;
  report.environment_corrections = 0;
  report.max_speed_mm_s = 0.0f;
  for (uint16_t s = 0; s < substeps; ++s) {
    const Motion motion = integrate_once(m, h, integrator, st);
    if (motion.bad > 0) return false;
    report.environment_corrections += apply_environment(m);
    report.max_speed_mm_s = std::max(report.max_speed_mm_s, motion.max_speed_mm_s);
  }
  return true;
}

void configure(const Dynamics& d, DeformState& st) {
  const uint16_t substeps = std::max<uint16_t>(d.substeps, 1);
  const bool changed = !st.configured || d.integrator != st.configured_integrator ||
                       substeps != st.configured_substeps;
  const bool recovered =
      st.status.in_use != st.configured_integrator || st.status.substeps_in_use != substeps;
  const bool probe =
      st.guard.probe_after_steps > 0 && recovered && st.clean_steps >= st.guard.probe_after_steps;
  if (!changed && !probe) return;
  st.configured = true;
  st.configured_integrator = d.integrator;
  st.configured_substeps = substeps;
  st.status.in_use = d.integrator;
  st.status.substeps_in_use = substeps;
  st.clean_steps = 0;
}

}  // namespace

StepReport step(Membrane& m, double dt_s, DeformState& st) {
  StepReport report;
  configure(m.dynamics, st);
  report.integrator = st.status.in_use;
  report.substeps = st.status.substeps_in_use;
  report.rejected_loads = count_rejected_loads(m);
  st.rejected_loads += report.rejected_loads;
  report.repaired_particles = sanitize_and_save(m, st.snapshot);
  st.repaired_particles += report.repaired_particles;
  if (!(dt_s > 0.0) || !std::isfinite(dt_s)) return report;  // nothing to integrate; state is clean

  const GuardSettings& guard = st.guard;
  const uint16_t max_substeps = std::max<uint16_t>(guard.max_substeps, 1);
  if (guard.check_energy) report.energy_before = measure_energy(m);
  Integrator integrator = st.status.in_use;
  uint16_t substeps = st.status.substeps_in_use;
  for (;;) {
    ++report.attempts;
    bool ok = run_attempt(m, dt_s, integrator, substeps, st, report);
    if (ok && guard.check_energy) {
      report.energy_after = measure_energy(m);
      ok = !energy_diverged(report.energy_before, report.energy_after, guard.energy);
    }
    if (ok) break;
    report.diverged = true;
    restore_state(m, st.snapshot);
    if (substeps <= max_substeps / 2) {
      substeps = static_cast<uint16_t>(substeps * 2);
    } else if (integrator != guard.fallback) {
      integrator = guard.fallback;
      substeps = 1;
      report.fell_back = true;
    } else {
      hold_still(m);
      report.held = true;
      report.max_speed_mm_s = 0.0f;
      report.environment_corrections = 0;
      if (guard.check_energy) report.energy_after = measure_energy(m);
      break;
    }
  }

  report.integrator = integrator;
  report.substeps = substeps;
  DynamicsStatus& status = st.status;
  ++status.steps;
  status.divergences += report.diverged ? 1 : 0;
  status.fallbacks += report.fell_back ? 1 : 0;
  st.holds += report.held ? 1 : 0;
  status.in_use = integrator;
  status.substeps_in_use = substeps;
  status.max_speed_mm_s = report.max_speed_mm_s;
  st.clean_steps = report.diverged ? 0 : st.clean_steps + 1;
  return report;
}

}  // namespace phaco::deform
