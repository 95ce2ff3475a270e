#include "perf/membrane_methods.hpp"

#include <algorithm>
#include <cmath>
#include <functional>
#include <memory>

#include "engine/core/clock.hpp"
#include "perf/peers/bullet_membrane.hpp"
#include "perf/timing.hpp"
#include "procedures/reference/static_solve.hpp"
#include "systems/active_nodes/active_nodes.hpp"
#include "systems/deform/explicit.hpp"
#include "systems/deform/forces.hpp"
#include "systems/deform/implicit.hpp"
#include "systems/deform/stability.hpp"
#include "systems/deform/xpbd.hpp"
#include "systems/force_propagation/force_propagation.hpp"
#include "systems/springs/springs.hpp"

namespace phaco::perf {

namespace {

constexpr double kFrame = 1.0 / 120;
constexpr double kLoadMn = 0.01;  // small: deflection ~10 µm, far inside the linear regime

// One deform integrator with its scratch, stepping a Membrane view of a fixture.
struct DeformRunner {
  Integrator integrator;
  Dynamics dynamics;
  std::vector<deform::PointLoad> loads;
  std::vector<float> axial;
  deform::ImplicitCache implicit;
  deform::XpbdScratch xpbd;

  void step(MembraneFixture& f, double dt) {
    deform::Membrane m{f.particles, f.springs, f.blocks, f.forces, dynamics};
    m.loads = loads;
    switch (integrator) {
      case Integrator::ExplicitEuler:
        deform::explicit_euler_step(m, dt);
        break;
      case Integrator::SymplecticEuler:
        deform::symplectic_euler_step(m, dt);
        break;
      case Integrator::SemiImplicit001:
        deform::semi_implicit_001_step(m, dt, axial);
        break;
      case Integrator::ImplicitEuler:
        deform::implicit_euler_step(m, dt, implicit);
        break;
      case Integrator::ImplicitPredictor:
        deform::implicit_predictor_step(m, dt, implicit);
        break;
      case Integrator::Xpbd:
        deform::xpbd_step(m, dt, xpbd);
        break;
    }
  }
};

// Fundamental mode of a pinned disc under tension T: ω1 = (j01/R)·√(T/(ρh)), j01 = 2.405.
double tension_estimate(const MembraneFixture& f) {
  const double p = f.options.prestretch;
  return 1.5 * f.options.youngs_modulus_kpa * f.options.thickness_mm * p / (1.0 - p);
}

double critical_viscosity(const MembraneFixture& f) {
  const double rho_h = f.options.density_kg_m3 * 1e-9 * f.options.thickness_mm;
  return 2.0 * 2.405 / f.radius_mm * std::sqrt(tension_estimate(f) / rho_h);
}

// Moves the fixture to its unloaded static equilibrium (the in-plane imbalance of an irregular
// pre-stretched mesh relaxed), so every method starts from rest.
void relax(MembraneFixture& f) {
  reference::StaticNetwork net = reference::network_from(f.particles, f.springs, f.options.law);
  reference::solve_static(net);
  for (uint32_t v = 0; v < f.vertex_count(); ++v) {
    f.particles.x[v] = static_cast<float>(net.x[v].x());
    f.particles.y[v] = static_cast<float>(net.x[v].y());
    f.particles.z[v] = static_cast<float>(net.x[v].z());
    f.particles.vx[v] = f.particles.vy[v] = f.particles.vz[v] = 0.0f;
  }
}

std::vector<float> positions(const Particles& p) {
  std::vector<float> s;
  s.reserve(3 * p.slots.size());
  for (uint32_t v = 0; v < p.slots.size(); ++v) s.insert(s.end(), {p.x[v], p.y[v], p.z[v]});
  return s;
}

void restore(MembraneFixture& f, const std::vector<float>& s) {
  for (uint32_t v = 0; v < f.vertex_count(); ++v) {
    f.particles.x[v] = s[3 * v], f.particles.y[v] = s[3 * v + 1], f.particles.z[v] = s[3 * v + 2];
    f.particles.vx[v] = f.particles.vy[v] = f.particles.vz[v] = 0.0f;
  }
  f.forces.resize_zero(f.vertex_count());
}

}  // namespace

std::vector<CostSample> measure_costs(MembraneFixture& f, int threads, double min_seconds,
                                      bool with_bullet) {
  std::vector<CostSample> out;
  const std::vector<float> start = positions(f.particles);
  const double dt = f.stable_dt();
  const float c = static_cast<float>(critical_viscosity(f));
  // A load that keeps changing, so iterative solvers always have work: 50 Hz, 0.01 mN.
  double t = 0;
  auto load_now = [&](double dt_step) {
    t += dt_step;
    return static_cast<float>(-kLoadMn * std::sin(2 * M_PI * 50 * t));
  };
  auto time = [&](const std::string& name, double step_dt, const std::string& note,
                  const std::function<void()>& fn) {
    restore(f, start);
    t = 0;
    out.push_back({name, seconds_per_call(threads, min_seconds, 3, fn), step_dt, note});
  };
  time("spring pass", dt, "springs::add_spring_forces", [&] {
    springs::add_spring_forces(f.springs, f.blocks, f.options.law, f.particles, f.forces);
  });
  f.forces.resize_zero(f.vertex_count());
  time("node pass", dt, "symplectic update + force reset",
       [&] { integrate_nodes(f.particles, f.forces, static_cast<float>(dt), c); });
  time("plain step", dt, "spring pass + node pass, dt = 0.9 x stable",
       [&] { plain_step(f, static_cast<float>(dt), c, f.centre, load_now(dt)); });

  struct Plan {
    const char* name;
    Integrator integrator;
    double dt;
    uint16_t xpbd_iterations;
  };
  const Plan plans[] = {
      {"explicit_euler", Integrator::ExplicitEuler, 0.1 * dt, 0},
      {"symplectic_euler", Integrator::SymplecticEuler, dt, 0},
      {"semi_implicit_001", Integrator::SemiImplicit001, kFrame, 0},
      {"implicit_euler", Integrator::ImplicitEuler, kFrame, 0},
      {"implicit_predictor", Integrator::ImplicitPredictor, kFrame, 0},
      {"xpbd", Integrator::Xpbd, kFrame, 8},
  };
  for (const Plan& plan : plans) {
    auto runner = std::make_unique<DeformRunner>();
    runner->integrator = plan.integrator;
    runner->dynamics.integrator = plan.integrator;
    runner->dynamics.law = f.options.law;
    runner->dynamics.viscosity_per_s = c;
    // Explicit Euler is unstable undamped at any dt; a drag above ω²·dt keeps it bounded.
    if (plan.integrator == Integrator::ExplicitEuler)
      runner->dynamics.damping_per_s = 2.0f * float(f.max_k_over_m * plan.dt);
    runner->loads = {{f.centre, 0, 0, 0}};
    runner->xpbd.iterations = plan.xpbd_iterations ? plan.xpbd_iterations : runner->xpbd.iterations;
    const std::string note = plan.dt < 1e-3 ? "dt near the explicit limit" : "dt = 1/120 s";
    time(plan.name, plan.dt, note, [&] {
      runner->loads[0].fz = load_now(plan.dt);
      runner->step(f, plan.dt);
    });
  }
  if (with_bullet && threads == 1) {
    restore(f, start);
    BulletMembraneOptions o;
    o.dt_s = kFrame;
    BulletMembrane bullet(f.particles, f.triangles, f.springs, o);
    out.push_back(
        {"btSoftBody",
         seconds_per_call(1, min_seconds, 3,
                          [&] {
                            bullet.add_force(f.centre, 0, 0, load_now(kFrame));
                            bullet.step();
                          }),
         kFrame,
         bullet.finite() ? "1 iteration, dt = 1/120 s" : "1 iteration, dt = 1/120 s: diverged"});
  }
  restore(f, start);
  return out;
}

ActiveSample measure_active_grasp(MembraneFixture& f, int threads, double min_seconds) {
  const std::vector<float> start = positions(f.particles);
  // The pre-stretched mesh is not exactly in balance as built (its in-plane imbalance is larger on
  // coarse meshes); a static relaxation costs minutes at 128k vertices, so instead the force wake
  // threshold sits above that residual: only the grasp and what it disturbs wake up.
  f.forces.resize_zero(f.vertex_count());
  springs::add_spring_forces(f.springs, f.blocks, f.options.law, f.particles, f.forces);
  double residual = 0;
  for (uint32_t v = 0; v < f.vertex_count(); ++v) {
    if (f.particles.kind[v] != ParticleKind::Free) continue;
    residual = std::max<double>(
        residual, std::sqrt(f.forces.fx[v] * f.forces.fx[v] + f.forces.fy[v] * f.forces.fy[v] +
                            f.forces.fz[v] * f.forces.fz[v]));
  }
  f.forces.resize_zero(f.vertex_count());
  const double force_threshold = std::max(1.0e-2, 2.0 * residual);
  const SpringGraph graph = springs::build_spring_graph(f.springs, f.vertex_count());
  active_nodes::ActiveSet set;
  Dynamics dyn;
  dyn.law = f.options.law;
  const uint32_t grasp = f.centre;
  f.particles.kind[grasp] = ParticleKind::Scripted;  // the forceps hold it
  const float dt = static_cast<float>(f.stable_dt());
  const float c = static_cast<float>(critical_viscosity(f));
  const uint32_t seeds[1] = {grasp};
  double t = 0;
  ActiveSample sample;
  auto step = [&] {
    t += dt;
    f.particles.z[grasp] =
        start[3 * grasp + 2] + static_cast<float>(0.05 * std::sin(2 * M_PI * 5 * t));
    active_nodes::WakeInputs wake;
    wake.particles = &f.particles;
    wake.dt_s = dt;
    wake.springs = &f.springs;
    wake.law = f.options.law;
    wake.force_threshold_mn = force_threshold;
    active_nodes::update_active_set(graph, seeds, 5, wake, set);
    for (uint32_t v : set.fell_asleep)
      f.particles.vx[v] = f.particles.vy[v] = f.particles.vz[v] = 0.0f;
    deform::Membrane m{f.particles, f.springs, f.blocks, f.forces, dyn};
    m.active = set.particles;
    m.active_springs = set.springs;
    deform::add_spring_forces_listed(m, set.springs, f.forces);
    const float keep = 1.0f - dt * c;
    for (uint32_t v : set.particles) {
      if (f.particles.kind[v] == ParticleKind::Free) {
        const float s = dt * f.particles.inv_mass[v];
        f.particles.vx[v] = keep * f.particles.vx[v] + s * f.forces.fx[v];
        f.particles.vy[v] = keep * f.particles.vy[v] + s * f.forces.fy[v];
        f.particles.vz[v] = keep * f.particles.vz[v] + s * f.forces.fz[v];
        f.particles.x[v] += dt * f.particles.vx[v];
        f.particles.y[v] += dt * f.particles.vy[v];
        f.particles.z[v] += dt * f.particles.vz[v];
      }
    }
    // Clear the accumulator where the restricted pass wrote: active particles and spring ends.
    for (uint32_t e : set.springs) {
      for (uint32_t v : {f.springs.i[e], f.springs.j[e]})
        f.forces.fx[v] = f.forces.fy[v] = f.forces.fz[v] = 0.0f;
    }
  };
  sample.seconds_per_step = seconds_per_call(threads, min_seconds, 3, step);
  sample.active_particles = static_cast<uint32_t>(set.particles.size());
  sample.active_springs = static_cast<uint32_t>(set.springs.size());
  f.particles.kind[grasp] = ParticleKind::Free;
  restore(f, start);
  return sample;
}

std::vector<AccuracySample> measure_accuracy(int level, bool quick, LoadCase* load_case) {
  FixtureOptions fo;
  fo.level = level;
  fo.flat = true;
  MembraneFixture f = make_membrane_fixture(fo);
  relax(f);
  const std::vector<float> rest = positions(f.particles);
  const float c = static_cast<float>(critical_viscosity(f));

  reference::StaticNetwork net = reference::network_from(f.particles, f.springs, f.options.law);
  net.external_force.assign(f.vertex_count(), Vec3::Zero());
  net.external_force[f.centre] = Vec3(0, 0, -kLoadMn);
  reference::solve_static(net);
  std::vector<double> u_ref(3 * f.vertex_count());
  double ref_norm2 = 0;
  for (uint32_t v = 0; v < f.vertex_count(); ++v) {
    for (int k = 0; k < 3; ++k) {
      u_ref[3 * v + k] = net.x[v][k] - rest[3 * v + k];
      if (f.particles.kind[v] == ParticleKind::Free)
        ref_norm2 += u_ref[3 * v + k] * u_ref[3 * v + k];
    }
  }
  if (load_case) {
    load_case->load_mn = kLoadMn;
    load_case->viscosity_per_s = c;
    load_case->frame_s = kFrame;
    load_case->reference_centre_deflection_mm = -u_ref[3 * f.centre + 2];
    load_case->tension_mn_mm = tension_estimate(f);
  }
  auto error_of = [&](auto&& pos) {
    double e2 = 0;
    for (uint32_t v = 0; v < f.vertex_count(); ++v) {
      if (f.particles.kind[v] != ParticleKind::Free) continue;
      float p[3];
      pos(v, p);
      for (int k = 0; k < 3; ++k) {
        const double d = (p[k] - rest[3 * v + k]) - u_ref[3 * v + k];
        e2 += d * d;
      }
    }
    return std::sqrt(e2 / ref_norm2);
  };
  auto particle_error = [&] {
    return error_of([&](uint32_t v, float* p) {
      p[0] = f.particles.x[v], p[1] = f.particles.y[v], p[2] = f.particles.z[v];
    });
  };
  std::vector<AccuracySample> out;
  auto record = [&](const std::string& method, const std::string& setting, double wall,
                    double err) {
    const bool ok = std::isfinite(err) && err < 1e6;
    out.push_back({method, setting, wall, wall / kFrame, ok ? err : NAN, ok});
  };

  // Plain explicit step with mass scaling: heavier particles, a longer stable step.
  for (double scale :
       quick ? std::vector<double>{1, 100, 1e4} : std::vector<double>{1, 10, 100, 1e3, 1e4, 1e5}) {
    restore(f, rest);
    for (uint32_t v = 0; v < f.vertex_count(); ++v)
      f.particles.inv_mass[v] /= static_cast<float>(scale);
    const double dt_stable = 0.9 * 2.0 / std::sqrt(f.max_k_over_m / scale);
    const int steps = static_cast<int>(std::ceil(kFrame / std::min(dt_stable, kFrame)));
    const float dt = static_cast<float>(kFrame / steps);
    const double wall = seconds_once(1, [&] {
      for (int s = 0; s < steps; ++s) plain_step(f, dt, c, f.centre, static_cast<float>(-kLoadMn));
    });
    record("plain step", "mass x" + std::to_string(static_cast<long>(scale)), wall,
           particle_error());
    for (uint32_t v = 0; v < f.vertex_count(); ++v)
      f.particles.inv_mass[v] *= static_cast<float>(scale);
  }

  // Deform integrators at 1/120 s split into substeps.
  struct Plan {
    const char* name;
    Integrator integrator;
    std::vector<int> substeps;
    uint16_t iterations;
  };
  const std::vector<Plan> plans = {
      {"semi_implicit_001", Integrator::SemiImplicit001,
       quick ? std::vector<int>{1, 16} : std::vector<int>{1, 4, 16, 64, 256}, 0},
      {"implicit_euler", Integrator::ImplicitEuler,
       quick ? std::vector<int>{1, 4} : std::vector<int>{1, 2, 4, 8, 16}, 0},
      {"implicit_predictor", Integrator::ImplicitPredictor,
       quick ? std::vector<int>{1, 4} : std::vector<int>{1, 2, 4, 8, 16}, 0},
      {"xpbd 8 it", Integrator::Xpbd,
       quick ? std::vector<int>{1, 4} : std::vector<int>{1, 4, 16, 64}, 8},
      {"xpbd 64 it", Integrator::Xpbd, quick ? std::vector<int>{1} : std::vector<int>{1, 4, 16},
       64},
  };
  for (const Plan& plan : plans) {
    for (int n : plan.substeps) {
      restore(f, rest);
      auto runner = std::make_unique<DeformRunner>();
      runner->integrator = plan.integrator;
      runner->dynamics.integrator = plan.integrator;
      runner->dynamics.law = f.options.law;
      runner->dynamics.viscosity_per_s = c;
      runner->loads = {{f.centre, 0, 0, static_cast<float>(-kLoadMn)}};
      if (plan.iterations) runner->xpbd.iterations = plan.iterations;
      const double dt = kFrame / n;
      // Factorisations and patterns are built on the first step: run an unloaded frame first, as a
      // running simulation has, then time the frame in which the load appears (the CG's warm start
      // is then the unloaded motion, not this frame's answer).
      runner->loads[0].fz = 0.0f;
      for (int s = 0; s < n; ++s) runner->step(f, dt);
      restore(f, rest);
      runner->loads[0].fz = static_cast<float>(-kLoadMn);
      const double wall = seconds_once(1, [&] {
        for (int s = 0; s < n; ++s) runner->step(f, dt);
      });
      record(plan.name, "dt 1/" + std::to_string(120 * n) + " s", wall, particle_error());
    }
  }

  // Force propagation, quasi-static: one propagation per frame.
  {
    const SpringGraph graph = springs::build_spring_graph(f.springs, f.vertex_count());
    force_propagation::PropagationScratch scratch;
    const uint32_t sources[1] = {f.centre};
    const float fz[1] = {static_cast<float>(-kLoadMn)}, zero[1] = {0.0f};
    const force_propagation::SourceForces forces{zero, zero, fz};
    const std::vector<std::pair<int, int>> settings =
        quick ? std::vector<std::pair<int, int>>{{8, 2}, {32, 16}}
              : std::vector<std::pair<int, int>>{{4, 1},   {8, 2},   {16, 4},
                                                 {32, 16}, {64, 64}, {128, 256}};
    for (const auto& [layers, sweeps] : settings) {
      restore(f, rest);
      force_propagation::PropagationSettings s;
      s.max_layers = layers;
      s.sweeps = sweeps;
      s.tolerance_mm = 1e-9;
      const double wall = seconds_once(1, [&] {
        force_propagation::propagate(f.particles, f.springs, f.options.law, graph, sources, s,
                                     scratch, &forces);
      });
      record("force propagation",
             std::to_string(layers) + " layers x " + std::to_string(sweeps) + " sweeps", wall,
             particle_error());
    }
  }

  // Bullet btSoftBody: Bullet's own fixed step dt = 1/120 s / n, 1 or more position iterations.
  for (int iterations : quick ? std::vector<int>{1, 10} : std::vector<int>{1, 10, 100}) {
    for (int n : quick ? std::vector<int>{1, 10} : std::vector<int>{1, 10, 100}) {
      restore(f, rest);
      BulletMembraneOptions o;
      o.dt_s = kFrame / n;
      o.position_iterations = iterations;
      BulletMembrane bullet(f.particles, f.triangles, f.springs, o);
      const double wall = seconds_once(1, [&] {
        for (int s = 0; s < n; ++s) {
          bullet.add_force(f.centre, 0, 0, static_cast<float>(-kLoadMn));
          bullet.step();
        }
      });
      const double err =
          bullet.finite()
              ? error_of([&](uint32_t v, float* p) { bullet.position(v, p[0], p[1], p[2]); })
              : NAN;
      record("btSoftBody " + std::to_string(iterations) + " it",
             "dt 1/" + std::to_string(120 * n) + " s", wall, err);
    }
  }
  return out;
}

std::vector<StabilitySample> measure_stability(bool quick) {
  // deform::stability_map on its rim-anchored patch probe: k over several decades at the capsule's
  // level-3 node mass and 100 times it; only k/m matters for the undamped schemes.
  const std::vector<double> k_values = quick
                                           ? std::vector<double>{0.01, 1, 100}
                                           : std::vector<double>{1e-3, 1e-2, 0.1, 1, 10, 100, 1000};
  const std::vector<double> masses = {1e-10, 1e-8};
  deform::StabilityProbe probe;
  if (quick) probe.bisections = 12;
  std::vector<StabilitySample> out;
  for (Integrator integrator :
       {Integrator::ExplicitEuler, Integrator::SymplecticEuler, Integrator::SemiImplicit001,
        Integrator::ImplicitEuler, Integrator::ImplicitPredictor, Integrator::Xpbd}) {
    const deform::StabilityMap map = deform::stability_map(integrator, k_values, masses, probe);
    for (size_t ik = 0; ik < k_values.size(); ++ik) {
      for (size_t im = 0; im < masses.size(); ++im) {
        const deform::StabilityResult& r = map.cells[ik * masses.size() + im];
        const double k_over_m = k_values[ik] / masses[im];
        // Patch probe: omega_max ~ sqrt(8 k/m), so symplectic Euler's bound is 2/sqrt(8 k/m).
        const double theory =
            integrator == Integrator::SymplecticEuler ? 2.0 / std::sqrt(8.0 * k_over_m) : 0.0;
        out.push_back({std::string(to_string(integrator)), k_over_m, r.dt_max_s, theory,
                       r.stable_everywhere, r.unstable_everywhere});
      }
    }
  }
  std::sort(out.begin(), out.end(), [](const StabilitySample& a, const StabilitySample& b) {
    return a.method != b.method ? a.method < b.method : a.k_over_m < b.k_over_m;
  });
  return out;
}

}  // namespace phaco::perf
