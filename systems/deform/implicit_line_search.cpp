// Backtracking on backward Euler's incremental potential, shared by implicit Euler and the
// predictor; see implicit.hpp for Φ and why the step needs it.
//
// Two forms with the same terms: line_search (the predictor's, a serial sum with its first two
// evaluations side by side) and line_search_on_team (implicit Euler's, on the step's team of
// threads, engine/schedule/phased_team.hpp). The team form works the unknowns and the springs in
// chunks fixed by the unknown count and sums the chunks' partials in chunk order, so Φ has the same
// bits on one thread and two:
//   phase 0       Δx = dt·(v + Δv) for the chunk's rows; partials of Φ(0) and Φ(1)
//   phase h ≥ 1   partials of Φ(2⁻ʰ), opened only while no α so far was accepted
// Most steps stop after phase 0.
#include <algorithm>
#include <cmath>

#include "engine/schedule/parallel.hpp"
#include "engine/schedule/phased_team.hpp"
#include "systems/deform/implicit.hpp"
#include "systems/deform/implicit_solver.hpp"

namespace phaco::deform::implicit_detail {

namespace {

// From this many unknowns the line search's first two evaluations run side by side (a task costs
// a few microseconds; one evaluation over 256 unknowns and their springs costs about ten).
constexpr size_t kParallelPotentialUnknowns = 256;

// What Φ's terms need besides the particles: fixed over a step.
struct PotentialConstants {
  double dt, drag, glue_k;
  bool glued;
};

PotentialConstants potential_constants(const Membrane& m, double dt) {
  const Dynamics& dyn = m.dynamics;
  const bool glued = m.glue && m.glue->x.size() == m.particles.slots.size();
  return {dt, double(dyn.damping_per_s) + dyn.viscosity_per_s,
          glued ? double(dyn.glue_stiffness_mn_mm) : 0.0, glued};
}

double coordinate(const Particles& p, uint32_t i, int a) {
  return a == 0 ? p.x[i] : a == 1 ? p.y[i] : p.z[i];
}

// Adds unknown particle i's inertia, drag, glue and weight at displacement dx (3, mm) to phi, axis
// by axis (the order the sums have always had).
void add_unknown_potential(const Membrane& m, const PotentialConstants& c, uint32_t i,
                           const double dx[3], double& phi) {
  const Particles& p = m.particles;
  const Dynamics& dyn = m.dynamics;
  const double true_mass = 1.0 / p.inv_mass[i];
  const double mass = mass_scale(dyn) * true_mass;
  const double v[3] = {p.vx[i], p.vy[i], p.vz[i]};
  const double dt = c.dt;
  for (int a = 0; a < 3; ++a) {
    const double x = coordinate(p, i, a) + dx[a];
    const double inertial = dx[a] - dt * v[a];
    const double rest = c.glued ? (a == 0   ? m.glue->x[i]
                                   : a == 1 ? m.glue->y[i]
                                            : m.glue->z[i])
                                : x;
    phi += mass / (2.0 * dt * dt) * inertial * inertial +
           mass * c.drag / (2.0 * dt) * dx[a] * dx[a] + 0.5 * c.glue_k * (x - rest) * (x - rest) -
           true_mass * dyn.gravity_mm_s2[a] * x;
  }
}

// Spring e's elastic energy with its ends at distance (dx, dy, dz).
double spring_potential_of(const Membrane& m, uint32_t e, double dx, double dy, double dz) {
  const Springs& s = m.springs;
  const double ext = std::sqrt(dx * dx + dy * dy + dz * dz) - s.rest_length[e];
  return m.dynamics.law == SpringLaw::Linear ? 0.5 * s.stiffness[e] * ext * ext
                                             : s.stiffness[e] * std::fabs(ext) * ext * ext / 3.0;
}

// Subtracts the point loads' work, −F·x (a constant force's potential), at positions at(i, a).
template <class At>
void add_load_potential(const Membrane& m, std::span<const uint32_t> unknown_of, At&& at,
                        double& phi) {
  for (const PointLoad& load : m.loads) {
    if (load.particle >= unknown_of.size() || unknown_of[load.particle] == kNotUnknown) continue;
    if (!std::isfinite(load.fx) || !std::isfinite(load.fy) || !std::isfinite(load.fz)) continue;
    phi -= load.fx * at(load.particle, 0) + load.fy * at(load.particle, 1) +
           load.fz * at(load.particle, 2);
  }
}

// Φ(x_n + α·Δx) over the unknowns and `springs`; the terms the step cannot change are left out.
double incremental_potential(const Membrane& m, double dt, std::span<const uint32_t> unknowns,
                             std::span<const uint32_t> unknown_of,
                             std::span<const uint32_t> springs, const double* step_dx,
                             double alpha) {
  const Particles& p = m.particles;
  const Springs& s = m.springs;
  const PotentialConstants c = potential_constants(m, dt);
  auto at = [&](uint32_t i, int a) {
    const uint32_t u = unknown_of[i];
    return u == kNotUnknown ? coordinate(p, i, a)
                            : coordinate(p, i, a) + alpha * step_dx[3 * u + a];
  };
  double phi = 0.0;
  for (size_t u = 0; u < unknowns.size(); ++u) {
    const double dx[3] = {alpha * step_dx[3 * u], alpha * step_dx[3 * u + 1],
                          alpha * step_dx[3 * u + 2]};
    add_unknown_potential(m, c, unknowns[u], dx, phi);
  }
  add_load_potential(m, unknown_of, at, phi);
  for (uint32_t e : springs) {
    const uint32_t i = s.i[e], j = s.j[e];
    phi += spring_potential_of(m, e, at(j, 0) - at(i, 0), at(j, 1) - at(i, 1), at(j, 2) - at(i, 2));
  }
  return phi;
}

bool accepted(double phi, double phi0) {
  return phi <= phi0 + 1e-12 * std::fabs(phi0);
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

double line_search_on_team(const Membrane& m, double dt, ImplicitCache& cache, PhasedTeam& team) {
  const Particles& p = m.particles;
  const Springs& s = m.springs;
  const UnknownSet& set = cache.unknowns;
  StepSystem& sys = cache.system;
  const uint32_t nu = static_cast<uint32_t>(set.particles.size());
  const uint32_t ns = static_cast<uint32_t>(set.springs.size());
  const int max_halvings = cache.settings.max_line_search_halvings;
  const PotentialConstants c = potential_constants(m, dt);
  // The assembly's chunks (implicit_euler.cpp): a thread keeps the rows it assembled.
  const uint32_t chunks = even_chunk_count(nu, cache.settings.parallel_grain_rows);
  const uint32_t rows_per = (nu + chunks - 1) / chunks, springs_per = (ns + chunks - 1) / chunks;
  sys.step_dx.resize(3 * Eigen::Index(nu));
  // Per chunk: Φ(0) and Φ(α) partials (phase 0), then Φ(α) of each halving.
  sys.potential_start.assign(chunks, 0.0);
  sys.potential_trial.assign(chunks, 0.0);
  const double* dv = sys.dv.data();
  double* step_dx = sys.step_dx.data();
  const std::span<const uint32_t> unknown_of = set.unknown_of;

  // Δx of unknown u (particle i) on axis a, as phase 0 writes it: phase 0's spring terms need the
  // Δx of rows other chunks are still writing, so they recompute it (the same expression, the
  // same bits).
  const auto step_of = [&](uint32_t u, uint32_t i, int a) {
    const double v = a == 0 ? p.vx[i] : a == 1 ? p.vy[i] : p.vz[i];
    return dt * (v + dv[3 * size_t(u) + a]);
  };
  // The gate's state: the α the last phase evaluated; set once a step is accepted or the halvings
  // ran out. The gate runs alone between phases (phased_team.hpp), so plain variables will do.
  double alpha = 1.0, phi0 = 0.0;
  int halvings = 0;
  bool decided = max_halvings <= 0;
  const auto total = [&](const std::vector<double>& parts, double a) {
    double phi = 0.0;
    for (double v : parts) phi += v;  // chunk order: the same bits whoever ran which chunk
    add_load_potential(
        m, unknown_of,
        [&](uint32_t i, int axis) {
          const uint32_t u = unknown_of[i];
          return u == kNotUnknown ? coordinate(p, i, axis)
                                  : coordinate(p, i, axis) + a * step_dx[3 * size_t(u) + axis];
        },
        phi);
    return phi;
  };
  const auto gate = [&](uint64_t phase) {
    if (phase == 0) return true;
    if (decided) return false;
    if (phase == 1) phi0 = total(sys.potential_start, 0.0);
    if (accepted(total(sys.potential_trial, alpha), phi0)) {
      decided = true;
      return false;
    }
    alpha *= 0.5, ++halvings;
    if (halvings >= max_halvings) {  // α = 2⁻ᵐᵃˣ, taken without a test (line_search's rule)
      decided = true;
      return false;
    }
    return true;
  };
  const auto work = [&](uint64_t phase, uint32_t chunk) {
    const uint32_t ub = std::min(nu, chunk * rows_per), ue = std::min(nu, (chunk + 1) * rows_per);
    const uint32_t sb = std::min(ns, chunk * springs_per),
                   se = std::min(ns, (chunk + 1) * springs_per);
    if (phase == 0) {
      double start = 0.0, trial = 0.0;
      for (uint32_t u = ub; u < ue; ++u) {
        const uint32_t i = set.particles[u];
        double dx[3];
        for (int a = 0; a < 3; ++a) step_dx[3 * size_t(u) + a] = dx[a] = step_of(u, i, a);
        if (decided) continue;
        const double zero[3] = {0.0, 0.0, 0.0};
        add_unknown_potential(m, c, i, zero, start);
        add_unknown_potential(m, c, i, dx, trial);
      }
      if (!decided) {
        for (uint32_t t = sb; t < se; ++t) {
          const uint32_t e = set.springs[t], i = s.i[e], j = s.j[e];
          const uint32_t ui = unknown_of[i], uj = unknown_of[j];
          double d0[3] = {}, d1[3] = {};
          for (int a = 0; a < 3; ++a) {
            d0[a] = coordinate(p, j, a) - coordinate(p, i, a);
            const double xi =
                ui == kNotUnknown ? coordinate(p, i, a) : coordinate(p, i, a) + step_of(ui, i, a);
            const double xj =
                uj == kNotUnknown ? coordinate(p, j, a) : coordinate(p, j, a) + step_of(uj, j, a);
            d1[a] = xj - xi;
          }
          start += spring_potential_of(m, e, d0[0], d0[1], d0[2]);
          trial += spring_potential_of(m, e, d1[0], d1[1], d1[2]);
        }
      }
      sys.potential_start[chunk] = start, sys.potential_trial[chunk] = trial;
      return;
    }
    double trial = 0.0;
    for (uint32_t u = ub; u < ue; ++u) {
      const double dx[3] = {alpha * step_dx[3 * size_t(u)], alpha * step_dx[3 * size_t(u) + 1],
                            alpha * step_dx[3 * size_t(u) + 2]};
      add_unknown_potential(m, c, set.particles[u], dx, trial);
    }
    const auto at = [&](uint32_t i, uint32_t u, int a) {
      return u == kNotUnknown ? coordinate(p, i, a)
                              : coordinate(p, i, a) + alpha * step_dx[3 * size_t(u) + a];
    };
    for (uint32_t t = sb; t < se; ++t) {
      const uint32_t e = set.springs[t], i = s.i[e], j = s.j[e];
      const uint32_t ui = unknown_of[i], uj = unknown_of[j];
      trial += spring_potential_of(m, e, at(j, uj, 0) - at(i, ui, 0), at(j, uj, 1) - at(i, ui, 1),
                                   at(j, uj, 2) - at(i, ui, 2));
    }
    sys.potential_trial[chunk] = trial;
  };
  team.run(chunks, uint64_t(std::max(max_halvings, 0)) + 1, gate, work);
  return alpha;
}

}  // namespace phaco::deform::implicit_detail
