#include "procedures/reference/stiffness_isotropy.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <numbers>

#include "procedures/reference/static_solve.hpp"
#include "systems/springs/springs.hpp"

namespace phaco::reference {
namespace {

struct Spread {
  double mean, spread;
};

Spread spread_of(const std::vector<double>& v) {
  double sum = 0.0, lo = v.front(), hi = v.front();
  for (double x : v) sum += x, lo = std::min(lo, x), hi = std::max(hi, x);
  const double mean = sum / static_cast<double>(v.size());
  return {mean, (hi - lo) / mean};
}

// Least-squares Voigt stiffness from per-direction stresses; returns S = C⁻¹ and the misfit.
struct Fit {
  Eigen::Matrix3d compliance;
  double residual;
};

Fit fit_stiffness(const std::vector<double>& angles_deg, double strain,
                  const std::vector<Eigen::Vector3d>& stress) {
  const size_t nd = angles_deg.size();
  Eigen::MatrixXd a = Eigen::MatrixXd::Zero(3 * nd, 6);
  Eigen::VectorXd b(3 * nd);
  for (size_t k = 0; k < nd; ++k) {
    const double th = angles_deg[k] * std::numbers::pi / 180.0, co = std::cos(th),
                 si = std::sin(th);
    // Unknowns (C11, C22, C33, C12, C13, C23); engineering strain (ε c², ε s², 2ε c s).
    const double e1 = strain * co * co, e2 = strain * si * si, e3 = 2.0 * strain * co * si;
    const size_t r = 3 * k;
    a(r, 0) = e1, a(r, 3) = e2, a(r, 4) = e3, b[r] = stress[k][0];
    a(r + 1, 3) = e1, a(r + 1, 1) = e2, a(r + 1, 5) = e3, b[r + 1] = stress[k][1];
    a(r + 2, 4) = e1, a(r + 2, 5) = e2, a(r + 2, 2) = e3, b[r + 2] = stress[k][2];
  }
  const Eigen::VectorXd p = a.colPivHouseholderQr().solve(b);
  Eigen::Matrix3d cm;
  cm << p[0], p[3], p[4], p[3], p[1], p[5], p[4], p[5], p[2];
  return {cm.inverse(), (a * p - b).norm() / b.norm()};
}

double youngs_along(const Eigen::Matrix3d& s, double angle_deg) {
  const double th = angle_deg * std::numbers::pi / 180.0, co = std::cos(th), si = std::sin(th);
  const Eigen::Vector3d m(co * co, si * si, co * si);
  return 1.0 / m.dot(s * m);
}

double poisson_of(const Eigen::Matrix3d& s) {
  return -0.5 * (s(0, 1) / s(0, 0) + s(0, 1) / s(1, 1));
}

}  // namespace

IsotropyRow stiffness_isotropy(const IsotropyCase& c) {
  IsotropyRow row;
  row.layout = c.layout, row.weighting = c.weighting, row.level = c.level;
  row.continuum_youngs_mn_mm = c.sheet_modulus_mn_mm;
  const FlatDisc disc = make_flat_disc(c.radius_mm, 1000u << c.level, c.layout, c.seed);
  const DiscBody body = make_disc_body(disc);
  const Springs springs = springs::build_springs(
      body.particles, body.triangles,
      springs::SpringMaterial{SpringLaw::Linear, c.weighting, c.sheet_modulus_mn_mm, 0.0});
  row.vertices = body.particles.slots.size();

  StaticNetwork base = network_from(body.particles, springs, SpringLaw::Linear);
  for (size_t v = 0; v < base.x.size(); ++v) base.x[v] = disc.mesh.vertices[v];
  base.planar = true;
  // Rest lengths exactly the double-precision mesh lengths: no stress before the stretch.
  double sum_l = 0.0, sum_l2 = 0.0;
  for (size_t s = 0; s < base.i.size(); ++s) {
    base.rest_length[s] = (base.x[base.j[s]] - base.x[base.i[s]]).norm();
    sum_l += base.rest_length[s], sum_l2 += base.rest_length[s] * base.rest_length[s];
  }
  const double ns = static_cast<double>(base.i.size());
  row.edge_length_cv =
      std::sqrt(std::max(sum_l2 / ns - (sum_l / ns) * (sum_l / ns), 0.0)) / (sum_l / ns);
  double area = 0.0;
  for (const auto& t : disc.mesh.triangles)
    area += 0.5 * std::fabs((base.x[t[1]] - base.x[t[0]]).cross(base.x[t[2]] - base.x[t[0]]).z());

  std::vector<Eigen::Vector3d> stress;  // Voigt (xx, yy, xy) per direction
  for (double angle : c.angles_deg) {
    const double th = angle * std::numbers::pi / 180.0, co = std::cos(th), si = std::sin(th);
    StaticNetwork net = base;
    for (size_t v = 0; v < net.x.size(); ++v) {
      if (!net.fixed[v]) continue;
      const double along = c.strain * (co * net.x[v].x() + si * net.x[v].y());
      net.x[v].x() += along * co;
      net.x[v].y() += along * si;
    }
    const StaticResult res = solve_static(net, {1e-12, 40});
    row.worst_residual_mn = std::max(row.worst_residual_mn, res.residual_mn);
    const std::vector<double> t = spring_tensions(net);
    Eigen::Vector3d all = Eigen::Vector3d::Zero();
    for (size_t s = 0; s < t.size(); ++s) {
      const Vec3 d = net.x[net.j[s]] - net.x[net.i[s]];
      const double q = t[s] / d.norm();
      const Eigen::Vector3d v(q * d.x() * d.x(), q * d.y() * d.y(), q * d.x() * d.y());
      all += v;
    }
    stress.push_back(all / area);
    IsotropyDirection dir;
    dir.angle_deg = angle;
    dir.constrained_modulus_mn_mm = (stress.back()[0] * co * co + stress.back()[1] * si * si +
                                     2.0 * stress.back()[2] * co * si) /
                                    c.strain;
    row.directions.push_back(dir);
  }
  const Fit global = fit_stiffness(c.angles_deg, c.strain, stress);
  row.fit_residual = global.residual;
  row.poisson_ratio = poisson_of(global.compliance);
  std::vector<double> youngs, constrained;
  for (IsotropyDirection& dir : row.directions) {
    dir.youngs_modulus_mn_mm = youngs_along(global.compliance, dir.angle_deg);
    youngs.push_back(dir.youngs_modulus_mn_mm);
    constrained.push_back(dir.constrained_modulus_mn_mm);
  }
  const Spread ys = spread_of(youngs), cs = spread_of(constrained);
  row.youngs_mean = ys.mean, row.youngs_spread = ys.spread;
  row.constrained_mean = cs.mean, row.constrained_spread = cs.spread;
  row.youngs_mean_error = (row.youngs_mean - c.sheet_modulus_mn_mm) / c.sheet_modulus_mn_mm;
  return row;
}

std::vector<IsotropyRow> stiffness_isotropy_study(std::span<const DiscLayout> layouts,
                                                  std::span<const StiffnessWeighting> weightings,
                                                  const IsotropyCase& base) {
  std::vector<IsotropyRow> rows;
  for (DiscLayout layout : layouts)
    for (StiffnessWeighting w : weightings) {
      IsotropyCase c = base;
      c.layout = layout, c.weighting = w;
      rows.push_back(stiffness_isotropy(c));
    }
  return rows;
}

}  // namespace phaco::reference
