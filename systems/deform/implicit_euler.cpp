// Implicit Euler (Baraff & Witkin 1998) with Eigen's conjugate gradients; see implicit.hpp for the
// equations and implicit_solver.hpp for the operator and the preconditioners.
//
// One step, in order:
//   1. select the unknowns: free particles of the active set, and the springs touching them;
//   2. (re)build the block-CSR pattern when that selection changed (cuts call invalidate());
//   3. assemble f, the right side b and the 3×3 blocks of A at the current positions;
//   4. refresh the preconditioner (diagonals every step, factorisations with the pattern);
//   5. solve A·Δv = b by preconditioned CG from the last step's Δv;
//   6. line-search Φ along Δx = dt·(v + Δv) and move the unknowns.
#include <algorithm>
#include <cmath>
#include <optional>
#include <utility>

#include "engine/core/clock.hpp"
#include "engine/schedule/parallel.hpp"
#include "engine/schedule/phased_team.hpp"
#include "systems/deform/implicit.hpp"
#include "systems/deform/implicit_solver.hpp"

namespace phaco::deform {

SpringForceJacobian spring_force_jacobian(double dx, double dy, double dz, double rest_length,
                                          double stiffness, SpringLaw law) {
  SpringForceJacobian r;
  const double l = std::sqrt(dx * dx + dy * dy + dz * dz);
  if (!(l > 0.0)) return r;  // coincident ends: no direction, no force, no stiffness
  const double ux = dx / l, uy = dy / l, uz = dz / l;
  const double ext = l - rest_length;
  const double force =
      law == SpringLaw::Linear ? stiffness * ext : stiffness * ext * std::fabs(ext);
  const double axial = law == SpringLaw::Linear ? stiffness : 2.0 * stiffness * std::fabs(ext);
  const double transverse = std::max(force / l, 0.0);  // clamped under compression: stays PSD
  const double a = axial - transverse;
  r.force_on_i = {force * ux, force * uy, force * uz};
  r.k = {a * ux * ux + transverse, a * ux * uy, a * ux * uz,
         a * uy * uy + transverse, a * uy * uz, a * uz * uz + transverse};
  return r;
}

namespace {

bool is_unknown_kind(const Particles& p, uint32_t i) {
  return p.slots.alive(i) && p.kind[i] == ParticleKind::Free && p.inv_mass[i] > 0.0f;
}

uint32_t find_in_row(const BlockPattern& pattern, uint32_t u, uint32_t w) {
  const auto begin = pattern.col.begin() + pattern.row_begin[u],
             end = pattern.col.begin() + pattern.row_begin[u + 1];
  return static_cast<uint32_t>(std::lower_bound(begin, end, w) - begin);
}

// Per-particle arrays follow the particle table. A cut appends particles: grow and keep what is
// there (new particles are no unknown yet and start from a zero Δv), so a cut frame pays for the
// new particles only. A shrinking table (compaction renumbers particles) starts over.
void fit_particle_arrays(uint32_t n, ImplicitCache& cache) {
  UnknownSet& set = cache.unknowns;
  if (set.unknown_of.size() > n) {
    set.unknown_of.assign(n, kNotUnknown);
    cache.warm_dv.assign(3 * size_t(n), 0.0);
    set.particles.clear();
    cache.pattern.valid = false;
    return;
  }
  set.unknown_of.resize(n, kNotUnknown);
  cache.warm_dv.resize(3 * size_t(n), 0.0);
}

// Step 1. Unknowns are the free particles of the active set (all free particles without one);
// fixed particles (anchored, scripted, asleep) keep their place. Returns true when the unknowns
// or the springs differ from the last step's, i.e. when the pattern must be rebuilt.
bool select_unknowns(const Membrane& m, ImplicitCache& cache) {
  const Particles& p = m.particles;
  const Springs& s = m.springs;
  UnknownSet& set = cache.unknowns;
  const uint32_t n = p.slots.size();
  set.candidate_particles.clear();
  if (m.active.empty()) {
    for (uint32_t i = 0; i < n; ++i)
      if (is_unknown_kind(p, i)) set.candidate_particles.push_back(i);
  } else {
    for (uint32_t i : m.active)
      if (i < n && is_unknown_kind(p, i)) set.candidate_particles.push_back(i);
  }
  bool changed = !cache.pattern.valid || cache.pattern.built_for != cache.settings.cg_operator;
  if (set.candidate_particles != set.particles) {
    for (uint32_t i : set.particles)
      if (i < n) set.unknown_of[i] = kNotUnknown;
    set.particles.swap(set.candidate_particles);
    for (uint32_t u = 0; u < set.particles.size(); ++u) set.unknown_of[set.particles[u]] = u;
    changed = true;
  }
  set.candidate_springs.clear();
  auto consider = [&](uint32_t e) {
    if (s.slots.alive(e) &&
        (set.unknown_of[s.i[e]] != kNotUnknown || set.unknown_of[s.j[e]] != kNotUnknown))
      set.candidate_springs.push_back(e);
  };
  if (m.active.empty()) {
    for (uint32_t e = 0; e < s.slots.size(); ++e) consider(e);
  } else {
    for (uint32_t e : m.active_springs)
      if (e < s.slots.size()) consider(e);
  }
  if (set.candidate_springs != set.springs) {
    set.springs.swap(set.candidate_springs);
    changed = true;
  }
  return changed;
}

// Step 2. The block-CSR pattern of A over the unknowns: row u holds u and every unknown sharing a
// step spring with it, sorted; each spring remembers where its two off-diagonal blocks sit, so
// assembly writes blocks without searching.
void build_pattern(const Springs& s, ImplicitCache& cache) {
  const UnknownSet& set = cache.unknowns;
  BlockPattern& pattern = cache.pattern;
  const uint32_t nu = static_cast<uint32_t>(set.particles.size());
  const size_t ns = set.springs.size();
  pattern.spring_ui.resize(ns);
  pattern.spring_uj.resize(ns);
  pattern.row_begin.assign(nu + 1, 0);
  for (uint32_t u = 0; u < nu; ++u) pattern.row_begin[u + 1] = 1;  // the diagonal block
  for (size_t t = 0; t < ns; ++t) {
    const uint32_t e = set.springs[t];
    const uint32_t ui = set.unknown_of[s.i[e]], uj = set.unknown_of[s.j[e]];
    pattern.spring_ui[t] = ui, pattern.spring_uj[t] = uj;
    if (ui != kNotUnknown && uj != kNotUnknown)
      ++pattern.row_begin[ui + 1], ++pattern.row_begin[uj + 1];
  }
  for (uint32_t u = 0; u < nu; ++u) pattern.row_begin[u + 1] += pattern.row_begin[u];
  pattern.col.resize(pattern.row_begin[nu]);
  pattern.diag_pos.resize(nu);
  {
    std::vector<uint32_t>& fill = cache.unknowns.candidate_particles;  // free scratch at this point
    fill.assign(pattern.row_begin.begin(), pattern.row_begin.end() - 1);
    for (uint32_t u = 0; u < nu; ++u) pattern.col[fill[u]++] = u;
    for (size_t t = 0; t < ns; ++t) {
      const uint32_t ui = pattern.spring_ui[t], uj = pattern.spring_uj[t];
      if (ui == kNotUnknown || uj == kNotUnknown) continue;
      pattern.col[fill[ui]++] = uj;
      pattern.col[fill[uj]++] = ui;
    }
  }
  // Rows sort independently, and each spring finds its blocks on its own: both split over threads
  // (the active set changes in most frames, so this runs in most frames).
  const ImplicitSettings& settings = cache.settings;
  parallel_for(0u, nu, settings.parallel_grain_rows, [&pattern](uint32_t b, uint32_t e, int) {
    for (uint32_t u = b; u < e; ++u) {
      std::sort(pattern.col.begin() + pattern.row_begin[u],
                pattern.col.begin() + pattern.row_begin[u + 1]);
      pattern.diag_pos[u] = find_in_row(pattern, u, u);
    }
  });
  pattern.spring_pos_ij.resize(ns);
  pattern.spring_pos_ji.resize(ns);
  parallel_for(0u, uint32_t(ns), settings.parallel_grain_springs,
               [&pattern](uint32_t b, uint32_t e, int) {
                 for (uint32_t t = b; t < e; ++t) {
                   const uint32_t ui = pattern.spring_ui[t], uj = pattern.spring_uj[t];
                   const bool both = ui != kNotUnknown && uj != kNotUnknown;
                   pattern.spring_pos_ij[t] = both ? find_in_row(pattern, ui, uj) : kNotUnknown;
                   pattern.spring_pos_ji[t] = both ? find_in_row(pattern, uj, ui) : kNotUnknown;
                 }
               });
  // Each row's springs, in increasing t (the order the serial scatter added them in).
  pattern.row_spring_begin.assign(nu + 1, 0);
  for (size_t t = 0; t < ns; ++t) {
    if (pattern.spring_ui[t] != kNotUnknown) ++pattern.row_spring_begin[pattern.spring_ui[t] + 1];
    if (pattern.spring_uj[t] != kNotUnknown) ++pattern.row_spring_begin[pattern.spring_uj[t] + 1];
  }
  for (uint32_t u = 0; u < nu; ++u) pattern.row_spring_begin[u + 1] += pattern.row_spring_begin[u];
  pattern.row_spring.resize(pattern.row_spring_begin[nu]);
  {
    std::vector<uint32_t>& fill = cache.unknowns.candidate_particles;
    fill.assign(pattern.row_spring_begin.begin(), pattern.row_spring_begin.end() - 1);
    for (size_t t = 0; t < ns; ++t) {
      const uint32_t ui = pattern.spring_ui[t], uj = pattern.spring_uj[t];
      if (ui != kNotUnknown) pattern.row_spring[fill[ui]++] = uint32_t(2 * t);
      if (uj != kNotUnknown) pattern.row_spring[fill[uj]++] = uint32_t(2 * t + 1);
    }
  }
  if (cache.settings.cg_operator == CgOperator::Assembled)
    implicit_detail::write_matrix_pattern(pattern, cache.system.matrix);
  pattern.valid = true;
  pattern.built_for = cache.settings.cg_operator;
  ++cache.stats.pattern_builds;
}

inline void add_sym(Sym3& to, const Sym3& k, double s) {
  for (int q = 0; q < 6; ++q) to[q] += s * k[q];
}

// Step 3. Baraff & Witkin's system at the current state: f (springs, gravity, drag, glue, point
// loads), b = dt·(f + dt·K·v) with K = ∂f/∂x, and the blocks of
// A = M·(1 + dt·(γ+κ)) + dt²·(g·I − K): diagonal blocks m(1 + dt(γ+κ))·I + dt²(g·I + Σ k_e),
// off-diagonal blocks −dt²·k_e. A spring with one fixed end adds to its free end's diagonal only,
// and its fixed end brings no velocity term.
//
// Two passes, each split over threads (their results do not depend on the split): the springs'
// forces and blocks, then each row gathered from its own springs in increasing order, which adds
// the same terms in the same order as one serial scatter over the springs would.
// Springs [begin, end) of the step: force on i, block k and velocity term k·(v_j − v_i).
void spring_terms(const Membrane& m, ImplicitCache& cache, uint32_t begin, uint32_t end) {
  const Particles& p = m.particles;
  const Springs& s = m.springs;
  const UnknownSet& set = cache.unknowns;
  const BlockPattern& pattern = cache.pattern;
  StepSystem& sys = cache.system;
  for (uint32_t t = begin; t < end; ++t) {
    const uint32_t sp = set.springs[t], i = s.i[sp], j = s.j[sp];
    const SpringForceJacobian sj = spring_force_jacobian(
        double(p.x[j]) - p.x[i], double(p.y[j]) - p.y[i], double(p.z[j]) - p.z[i],
        s.rest_length[sp], s.stiffness[sp], m.dynamics.law);
    sys.spring_k[t] = sj.k;
    sys.spring_force[t] = sj.force_on_i;
    double vi[3] = {0.0, 0.0, 0.0}, vj[3] = {0.0, 0.0, 0.0};
    if (pattern.spring_ui[t] != kNotUnknown) vi[0] = p.vx[i], vi[1] = p.vy[i], vi[2] = p.vz[i];
    if (pattern.spring_uj[t] != kNotUnknown) vj[0] = p.vx[j], vj[1] = p.vy[j], vj[2] = p.vz[j];
    const double w[3] = {vj[0] - vi[0], vj[1] - vi[1], vj[2] - vi[2]};
    const Sym3& k = sj.k;
    sys.spring_kw[t] = {k[0] * w[0] + k[1] * w[1] + k[2] * w[2],
                        k[1] * w[0] + k[3] * w[1] + k[4] * w[2],
                        k[2] * w[0] + k[4] * w[1] + k[5] * w[2]};
  }
}

// The point loads on unknowns as (unknown, load), sorted: each row adds its own in list order.
void list_point_loads(const Membrane& m, ImplicitCache& cache) {
  std::vector<std::pair<uint32_t, uint32_t>>& loads = cache.system.loads;
  loads.clear();
  const std::vector<uint32_t>& unknown_of = cache.unknowns.unknown_of;
  for (uint32_t l = 0; l < m.loads.size(); ++l) {
    const PointLoad& load = m.loads[l];
    if (load.particle >= unknown_of.size() || unknown_of[load.particle] == kNotUnknown) continue;
    // Non-finite loads are rejected (and counted) by the guard's force pass; skip them here too.
    if (!std::isfinite(load.fx) || !std::isfinite(load.fy) || !std::isfinite(load.fz)) continue;
    loads.emplace_back(unknown_of[load.particle], l);
  }
  std::sort(loads.begin(), loads.end());
}

// Rows [ub, ue): each gathered from its springs in increasing order (see above).
void row_terms(const Membrane& m, double dt, ImplicitCache& cache, uint32_t ub, uint32_t ue) {
  const Particles& p = m.particles;
  const Dynamics& dyn = m.dynamics;
  const UnknownSet& set = cache.unknowns;
  const BlockPattern& pattern = cache.pattern;
  StepSystem& sys = cache.system;
  const double dt2 = dt * dt;
  const double drag = double(dyn.damping_per_s) + dyn.viscosity_per_s;
  const bool glued = m.glue && m.glue->x.size() == p.slots.size();
  const double glue_k = glued ? dyn.glue_stiffness_mn_mm : 0.0;
  auto load = std::lower_bound(sys.loads.begin(), sys.loads.end(), std::make_pair(ub, 0u));
  for (uint32_t u = ub; u < ue; ++u) {
    const uint32_t i = set.particles[u];
    // Mass scaling changes inertia only: the weight stays that of the true mass (docs/dynamics.md).
    const double true_mass = 1.0 / p.inv_mass[i];
    const double mass = implicit_detail::mass_scale(dyn) * true_mass;
    const double v[3] = {p.vx[i], p.vy[i], p.vz[i]};
    const double x[3] = {p.x[i], p.y[i], p.z[i]};
    double f[3], kv[3];  // f, and K·v (b's velocity term) until b is formed below
    for (int a = 0; a < 3; ++a) {
      const double rest = glued ? (a == 0   ? m.glue->x[i]
                                   : a == 1 ? m.glue->y[i]
                                            : m.glue->z[i])
                                : x[a];
      f[a] = true_mass * dyn.gravity_mm_s2[a] - mass * drag * v[a] - glue_k * (x[a] - rest);
      kv[a] = -glue_k * v[a];
    }
    for (; load != sys.loads.end() && load->first == u; ++load) {
      const PointLoad& pl = m.loads[load->second];
      f[0] += pl.fx, f[1] += pl.fy, f[2] += pl.fz;
    }
    Sym3* row = sys.block.data() + pattern.row_begin[u];
    std::fill(row, sys.block.data() + pattern.row_begin[u + 1], Sym3{});
    const double d = mass * (1.0 + dt * drag) + dt2 * glue_k;
    Sym3& diagonal = row[pattern.diag_pos[u]];
    diagonal = {d, 0.0, 0.0, d, 0.0, d};
    for (uint32_t r = pattern.row_spring_begin[u]; r < pattern.row_spring_begin[u + 1]; ++r) {
      const uint32_t t = pattern.row_spring[r] >> 1;
      const double sign = (pattern.row_spring[r] & 1u) ? -1.0 : 1.0;  // the j end: −force
      for (int a = 0; a < 3; ++a)
        f[a] += sign * sys.spring_force[t][a], kv[a] += sign * sys.spring_kw[t][a];
      const Sym3& k = sys.spring_k[t];
      add_sym(diagonal, k, dt2);
      if (pattern.spring_ui[t] != kNotUnknown && pattern.spring_uj[t] != kNotUnknown)
        add_sym(row[sign > 0.0 ? pattern.spring_pos_ij[t] : pattern.spring_pos_ji[t]], k, -dt2);
    }
    for (int a = 0; a < 3; ++a) {
      sys.force[3 * u + a] = f[a];
      sys.rhs[3 * u + a] = dt * f[a] + dt2 * kv[a];
    }
  }
}

// Whether this step forms its team of two (ImplicitSettings::team_policy; team_choice.hpp).
bool step_on_team(ImplicitCache& cache, uint32_t nodes) {
  const ImplicitSettings& s = cache.settings;
  if (worker_count() < 2 || nodes < s.cg_team_min_rows) return false;
  if (s.team_policy == TeamPolicy::Always) return true;
  return choose_team(cache.team_choice, nodes, {.min_nodes = s.cg_team_min_rows});
}

// Two phases on the step's team: the springs, then the rows, each in an even number of equal
// chunks (the team's two threads start from opposite ends).
void assemble(const Membrane& m, double dt, ImplicitCache& cache, PhasedTeam& team) {
  const uint32_t nu = static_cast<uint32_t>(cache.unknowns.particles.size());
  const uint32_t ns = static_cast<uint32_t>(cache.unknowns.springs.size());
  StepSystem& sys = cache.system;
  sys.spring_k.resize(ns);
  sys.spring_force.resize(ns);
  sys.spring_kw.resize(ns);
  list_point_loads(m, cache);
  sys.force.resize(3 * nu);
  sys.rhs.resize(3 * nu);
  sys.block.resize(cache.pattern.row_begin[nu]);
  const uint32_t chunks = implicit_detail::even_chunk_count(nu, cache.settings.parallel_grain_rows);
  const uint32_t rows_per = (nu + chunks - 1) / chunks, springs_per = (ns + chunks - 1) / chunks;
  team.run(
      chunks, 2, [](uint64_t) { return true; },
      [&](uint64_t phase, uint32_t c) {
        if (phase == 0)
          spring_terms(m, cache, std::min(ns, c * springs_per),
                       std::min(ns, (c + 1) * springs_per));
        else
          row_terms(m, dt, cache, std::min(nu, c * rows_per), std::min(nu, (c + 1) * rows_per));
      });
  if (cache.settings.cg_operator == CgOperator::Assembled)
    implicit_detail::write_matrix_values(cache.pattern, sys.block, sys.matrix);
}

// Steps 2–6 on the unknowns step 1 selected, on the threads implicit_euler_step chose.
void step_selected(Membrane& m, double dt, ImplicitCache& cache, bool set_changed, bool on_team,
                   bool timed) {
  Particles& p = m.particles;
  const uint32_t n = p.slots.size();
  if (set_changed) build_pattern(m.springs, cache);
  const UnknownSet& set = cache.unknowns;
  StepSystem& sys = cache.system;
  const size_t nu = set.particles.size();
  ++cache.stats.steps;
  cache.stats.unknowns = static_cast<uint32_t>(nu);
  cache.stats.springs = static_cast<uint32_t>(set.springs.size());
  cache.stats.nonzeros =
      9 * uint64_t(cache.pattern.row_begin.empty() ? 0 : cache.pattern.row_begin.back());
  if (nu == 0) {
    cache.stats.cg_iterations = 0, cache.stats.cg_residual = 0.0, cache.stats.cg_converged = true;
    return;
  }
  // A team for the assembly and the solve, formed now: its worker wakes while this thread
  // assembles (engine/schedule/phased_team.hpp). Let go before the solve if the solve is Eigen's,
  // whose parallel loops need the worker free.
  const int64_t team_from = now_ns();
  std::optional<PhasedTeam> team;
  team.emplace(on_team);
  assemble(m, dt, cache, *team);
  const bool row_chunked = cache.settings.cg_operator == CgOperator::MatrixFree &&
                           implicit_detail::team_cg_preconditioner(cache.settings.preconditioner);
  if (!row_chunked) team.reset();
  // Step 4. Diagonal preconditioners follow A every step; a factored one is rebuilt with the
  // pattern only (a stale factor is still SPD: CG stays valid, only its speed depends on it).
  implicit_detail::update_preconditioner(cache);

  // Warm start: a particle's Δv changes little from frame to frame while a tool pulls steadily.
  sys.guess.resize(3 * nu);
  for (size_t u = 0; u < nu; ++u)
    for (int a = 0; a < 3; ++a)
      sys.guess[3 * u + a] =
          cache.settings.warm_start ? cache.warm_dv[3 * set.particles[u] + a] : 0.0;
  // Step 5. CG to the relative tolerance (implicit_solver.hpp: operator and preconditioners).
  implicit_detail::solve_linear_system(cache, team ? &*team : nullptr);
  team.reset();
  cache.stats.cg_iterations_total += cache.stats.cg_iterations;
  if (on_team) ++cache.stats.team_steps;
  // The step's cost both ways, per node and iteration (two more for the assembly), for the next
  // steps' choice. Only where there was a choice: a single thread or a small set times nothing.
  if (timed)
    record_team_step(
        cache.team_choice, static_cast<uint32_t>(nu), on_team,
        double(now_ns() - team_from) / (double(nu) * double(cache.stats.cg_iterations + 2)),
        {.min_nodes = cache.settings.cg_team_min_rows});

  // Step 6. The linear solve is one Newton step of the incremental potential Φ (Gast et al. 2015);
  // at k·dt²/m ≈ 10⁷ a full step can overshoot where springs rotate or buckle, so take the largest
  // α in {1, ½, ...} that does not raise Φ.
  sys.step_dx.resize(3 * nu);
  for (size_t u = 0; u < nu; ++u) {
    const uint32_t i = set.particles[u];
    sys.step_dx[3 * u] = dt * (p.vx[i] + sys.dv[3 * u]);
    sys.step_dx[3 * u + 1] = dt * (p.vy[i] + sys.dv[3 * u + 1]);
    sys.step_dx[3 * u + 2] = dt * (p.vz[i] + sys.dv[3 * u + 2]);
  }
  const double alpha =
      implicit_detail::line_search(m, dt, cache.settings.max_line_search_halvings, set.particles,
                                   set.unknown_of, set.springs, sys.step_dx.data());
  cache.stats.step_fraction = alpha;
  if (alpha < 1.0) ++cache.stats.line_search_cuts;

  // Move the unknowns (x⁺ = x + α·Δx, v⁺ = α·Δx/dt) and keep the Δv actually taken for the next
  // warm start; the force written is the one at the start of the step.
  if (m.forces.fx.size() != n) m.forces.resize_zero(n);
  for (size_t u = 0; u < nu; ++u) {
    const uint32_t i = set.particles[u];
    const double dx = alpha * sys.step_dx[3 * u], dy = alpha * sys.step_dx[3 * u + 1],
                 dz = alpha * sys.step_dx[3 * u + 2];
    for (int a = 0; a < 3; ++a) {
      const double v_old = a == 0 ? p.vx[i] : a == 1 ? p.vy[i] : p.vz[i];
      cache.warm_dv[3 * i + a] = alpha * sys.step_dx[3 * u + a] / dt - v_old;
    }
    p.vx[i] = static_cast<float>(dx / dt), p.vy[i] = static_cast<float>(dy / dt),
    p.vz[i] = static_cast<float>(dz / dt);
    p.x[i] = static_cast<float>(p.x[i] + dx);
    p.y[i] = static_cast<float>(p.y[i] + dy);
    p.z[i] = static_cast<float>(p.z[i] + dz);
    m.forces.fx[i] = static_cast<float>(sys.force[3 * u]);
    m.forces.fy[i] = static_cast<float>(sys.force[3 * u + 1]);
    m.forces.fz[i] = static_cast<float>(sys.force[3 * u + 2]);
  }
}

}  // namespace

void implicit_euler_step(Membrane& m, double dt, ImplicitCache& cache) {
  fit_particle_arrays(m.particles.slots.size(), cache);
  const bool set_changed = select_unknowns(m, cache);
  const uint32_t nu = static_cast<uint32_t>(cache.unknowns.particles.size());
  // The step's threads: its team of two where that measured cheaper (team_choice.hpp), else this
  // thread alone for every loop of the step, not only CG's. The pattern's sort, the
  // preconditioner's blocks and the line search's two potentials would each wake the worker for a
  // few microseconds of work, and where the team lost, so do they (session 41: the 2-thread frame
  // 2–3 % faster at levels 3 and 6, docs/implicit_and_active.md).
  const bool two_threads = worker_count() >= 2;
  const bool on_team = step_on_team(cache, nu);
  const bool timed = two_threads && cache.settings.team_policy == TeamPolicy::Timed;
  if (two_threads && !on_team)
    cache.alone.run([&] { step_selected(m, dt, cache, set_changed, false, timed); });
  else
    step_selected(m, dt, cache, set_changed, on_team, timed);
}

}  // namespace phaco::deform
