#include "procedures/reference/membrane_disc.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "procedures/reference/static_solve.hpp"
#include "systems/springs/springs.hpp"

namespace phaco::reference {

const char* to_string(Pretension p) {
  return p == Pretension::Cotangent ? "cotangent" : "uniform_prestretch";
}

MembraneProfileRow membrane_profile(const MembraneCase& c) {
  MembraneProfileRow row;
  row.level = c.level, row.layout = c.layout, row.weighting = c.weighting, row.law = c.law;
  row.pretension = c.pretension;
  const FlatDisc disc = make_flat_disc(c.radius_mm, 1000u << c.level, c.layout);
  const DiscBody body = make_disc_body(disc);
  springs::SpringMaterial material{c.law, c.weighting, c.sheet_modulus_mn_mm, c.prestretch};
  material.pretension = c.pretension == Pretension::Cotangent
                            ? springs::Pretension::Cotangent
                            : springs::Pretension::UniformPrestretch;
  Springs springs = springs::build_springs(body.particles, body.triangles, material);
  row.vertices = body.particles.slots.size();
  row.springs = springs.slots.size();
  row.mean_edge_mm = mean_edge_length(disc.mesh);

  StaticNetwork net = network_from(body.particles, springs, c.law);
  for (size_t v = 0; v < net.x.size(); ++v) net.x[v] = disc.mesh.vertices[v];  // exact, double

  // 1. In-plane relaxation.
  net.planar = true;
  const StaticResult relaxed = solve_static(net, {1e-11, 60});
  row.relax_iterations = relaxed.iterations;

  // 2. Tension from the network: virial over the disc area.
  double area = 0.0;
  for (const auto& t : disc.mesh.triangles) {
    const Vec3 &a = net.x[t[0]], &b = net.x[t[1]], &d = net.x[t[2]];
    area += 0.5 * std::fabs((b - a).cross(d - a).z());
  }
  const std::vector<double> tension = spring_tensions(net);
  double virial = 0.0, radial = 0.0, hoop = 0.0;
  for (size_t s = 0; s < tension.size(); ++s) {
    const Vec3 d = net.x[net.j[s]] - net.x[net.i[s]];
    const double l = d.norm();
    const Vec3 mid = 0.5 * (net.x[net.j[s]] + net.x[net.i[s]]);
    const double rm = mid.head<2>().norm();
    const double cr = rm > 0 ? (d.x() * mid.x() + d.y() * mid.y()) / (l * rm) : 0.0;
    const double tl = tension[s] * l;
    virial += tl;
    radial += tl * cr * cr;
    hoop += tl * (1.0 - cr * cr);
  }
  row.tension_mn_mm = virial / (2.0 * area);
  row.tension_radial_mn_mm = radial / area;
  row.tension_hoop_mn_mm = hoop / area;

  // 3. Point load at the centre (vertex 0), full 3D equilibrium.
  const double T = row.tension_mn_mm, R = c.radius_mm;
  row.load_mn = 2.0 * std::numbers::pi * T * c.load_scale * R;
  net.planar = false;
  net.external_force.assign(net.x.size(), Vec3::Zero());
  net.external_force[0] = Vec3(0.0, 0.0, -row.load_mn);
  const StaticResult loaded = solve_static(net, {1e-8 * row.load_mn, 60});
  row.load_iterations = loaded.iterations;
  row.residual_mn = loaded.residual_mn;
  row.converged = relaxed.converged && loaded.converged;
  row.centre_deflection_mm = -net.x[0].z();

  // 4. Profile against w(r) = F ln(R/r)/(2πT).
  const double scale = row.load_mn / (2.0 * std::numbers::pi * T);
  const double r_core = c.core_radius_mm > 0 ? c.core_radius_mm : c.core_edges * row.mean_edge_mm;
  row.core_radius_mm = r_core;
  const double w_core = scale * std::log(R / r_core);
  double sum2 = 0.0;
  int count = 0;
  for (size_t v = 0; v < net.x.size(); ++v) {
    if (net.fixed[v]) continue;
    const double r = net.x[v].head<2>().norm();
    const double w = -net.x[v].z();
    const double wa = r > 0 ? scale * std::log(R / r) : 0.0;
    if (c.keep_samples) row.samples.push_back({r, w, wa});
    if (r < r_core) continue;
    row.max_scaled_error = std::max(row.max_scaled_error, std::fabs(w - wa) / w_core);
    if (r > R - r_core) continue;
    const double rel = std::fabs(w - wa) / wa;
    row.max_rel_error = std::max(row.max_rel_error, rel);
    sum2 += rel * rel;
    ++count;
  }
  row.rms_rel_error = count > 0 ? std::sqrt(sum2 / count) : 0.0;
  return row;
}

std::vector<MembraneProfileRow> membrane_profile_study(
    std::span<const int> levels, std::span<const DiscLayout> layouts,
    std::span<const StiffnessWeighting> weightings, std::span<const SpringLaw> laws,
    const MembraneCase& base) {
  std::vector<MembraneProfileRow> rows;
  for (int level : levels)
    for (DiscLayout layout : layouts)
      for (StiffnessWeighting weighting : weightings)
        for (SpringLaw law : laws) {
          MembraneCase c = base;
          c.level = level, c.layout = layout, c.weighting = weighting, c.law = law;
          rows.push_back(membrane_profile(c));
        }
  return rows;
}

OrderFit fit_order(std::span<const double> h, std::span<const double> error) {
  OrderFit fit;
  double sx = 0, sy = 0, sxx = 0, sxy = 0;
  for (size_t k = 0; k < std::min(h.size(), error.size()); ++k) {
    if (!(h[k] > 0) || !(error[k] > 0)) continue;
    const double x = std::log(h[k]), y = std::log(error[k]);
    sx += x, sy += y, sxx += x * x, sxy += x * y;
    ++fit.points;
  }
  const double n = fit.points;
  if (fit.points < 2 || n * sxx - sx * sx <= 0) return fit;
  fit.order = (n * sxy - sx * sy) / (n * sxx - sx * sx);
  fit.constant = std::exp((sy - fit.order * sx) / n);
  return fit;
}

}  // namespace phaco::reference
