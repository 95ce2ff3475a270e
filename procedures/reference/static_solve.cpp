#include "procedures/reference/static_solve.hpp"

#include <Eigen/SparseCholesky>
#include <Eigen/SparseCore>
#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace phaco::reference {

StaticNetwork network_from(const Particles& particles, const Springs& springs, SpringLaw law) {
  StaticNetwork net;
  const uint32_t n = particles.slots.size();
  net.x.resize(n);
  net.fixed.resize(n);
  for (uint32_t p = 0; p < n; ++p) {
    net.x[p] = Vec3(particles.x[p], particles.y[p], particles.z[p]);
    net.fixed[p] = particles.kind[p] != ParticleKind::Free ? 1 : 0;
  }
  for (uint32_t e = 0; e < springs.slots.size(); ++e) {
    if (!springs.slots.alive(e)) continue;
    net.i.push_back(springs.i[e]);
    net.j.push_back(springs.j[e]);
    net.rest_length.push_back(springs.rest_length[e]);
    net.stiffness.push_back(springs.stiffness[e]);
  }
  net.law = law;
  return net;
}

namespace {

double tension_of(SpringLaw law, double k, double ext) {
  return law == SpringLaw::Linear ? k * ext : k * ext * std::fabs(ext);
}

double energy_of(const StaticNetwork& net, const std::vector<Vec3>& x) {
  double e = 0.0;
  for (size_t s = 0; s < net.i.size(); ++s) {
    const double ext = (x[net.j[s]] - x[net.i[s]]).norm() - net.rest_length[s];
    e += net.law == SpringLaw::Linear ? 0.5 * net.stiffness[s] * ext * ext
                                      : net.stiffness[s] * std::fabs(ext) * ext * ext / 3.0;
  }
  if (!net.external_force.empty())
    for (size_t p = 0; p < x.size(); ++p) e -= net.external_force[p].dot(x[p]);
  return e;
}

std::vector<Vec3> forces_at(const StaticNetwork& net, const std::vector<Vec3>& x) {
  std::vector<Vec3> f(x.size(), Vec3::Zero());
  if (!net.external_force.empty()) f = net.external_force;
  for (size_t s = 0; s < net.i.size(); ++s) {
    const Vec3 d = x[net.j[s]] - x[net.i[s]];
    const double l = d.norm();
    if (l <= 0.0) continue;
    const Vec3 t = tension_of(net.law, net.stiffness[s], l - net.rest_length[s]) / l * d;
    f[net.i[s]] += t;
    f[net.j[s]] -= t;
  }
  return f;
}

double residual_of(const StaticNetwork& net, const std::vector<Vec3>& f) {
  double r = 0.0;
  for (size_t p = 0; p < f.size(); ++p) {
    if (net.fixed[p]) continue;
    const double m = net.planar ? std::hypot(f[p].x(), f[p].y()) : f[p].norm();
    r = std::max(r, m);
  }
  return r;
}

}  // namespace

std::vector<Vec3> net_forces(const StaticNetwork& network) {
  return forces_at(network, network.x);
}

std::vector<double> spring_tensions(const StaticNetwork& net) {
  std::vector<double> t(net.i.size());
  for (size_t s = 0; s < net.i.size(); ++s)
    t[s] = tension_of(net.law, net.stiffness[s],
                      (net.x[net.j[s]] - net.x[net.i[s]]).norm() - net.rest_length[s]);
  return t;
}

StaticResult solve_static(StaticNetwork& net, const StaticSettings& settings) {
  const size_t n = net.x.size();
  if (net.fixed.size() != n || (!net.external_force.empty() && net.external_force.size() != n))
    throw std::invalid_argument("solve_static: fixed and external_force must match the particles");
  const int dims = net.planar ? 2 : 3;
  std::vector<int> dof(n, -1);
  int dof_count = 0;
  for (size_t p = 0; p < n; ++p)
    if (!net.fixed[p]) dof[p] = dims * dof_count++;
  const int size = dims * dof_count;

  StaticResult result;
  std::vector<Vec3> f = forces_at(net, net.x);
  result.residual_mn = residual_of(net, f);
  result.energy = energy_of(net, net.x);
  if (size == 0 || result.residual_mn <= settings.tolerance_mn) {
    result.converged = true;
    return result;
  }

  using SpMat = Eigen::SparseMatrix<double>;
  Eigen::SimplicialLDLT<SpMat> ldlt;
  bool analysed = false;
  std::vector<Eigen::Triplet<double>> triplets;
  triplets.reserve(net.i.size() * 4 * dims * dims + size);
  SpMat h(size, size);
  Eigen::VectorXd g(size), step(size);
  std::vector<Vec3> trial(n);

  for (int it = 0; it < settings.max_iterations; ++it) {
    triplets.clear();
    double max_diag = 0.0;
    for (size_t s = 0; s < net.i.size(); ++s) {
      const uint32_t a = net.i[s], b = net.j[s];
      if (dof[a] < 0 && dof[b] < 0) continue;
      const Vec3 d = net.x[b] - net.x[a];
      const double l = d.norm();
      if (l <= 0.0) continue;
      const Vec3 u = d / l;
      const double ext = l - net.rest_length[s], k = net.stiffness[s];
      const double axial = net.law == SpringLaw::Linear ? k : 2.0 * k * std::fabs(ext);
      const double transverse = std::max(tension_of(net.law, k, ext), 0.0) / l;
      Eigen::Matrix3d blk = (axial - transverse) * (u * u.transpose());
      blk.diagonal().array() += transverse;
      for (int r = 0; r < dims; ++r)
        for (int c = 0; c < dims; ++c) {
          const double v = blk(r, c);
          if (dof[a] >= 0) triplets.emplace_back(dof[a] + r, dof[a] + c, v);
          if (dof[b] >= 0) triplets.emplace_back(dof[b] + r, dof[b] + c, v);
          if (dof[a] >= 0 && dof[b] >= 0) {
            triplets.emplace_back(dof[a] + r, dof[b] + c, -v);
            triplets.emplace_back(dof[b] + r, dof[a] + c, -v);
          }
        }
      max_diag = std::max(max_diag, blk.trace());
    }
    for (int q = 0; q < size; ++q) triplets.emplace_back(q, q, 0.0);  // keeps the pattern full
    h.setFromTriplets(triplets.begin(), triplets.end());
    for (size_t p = 0; p < n; ++p)
      if (dof[p] >= 0)
        for (int r = 0; r < dims; ++r) g[dof[p] + r] = -f[p][r];

    if (!analysed) {
      ldlt.analyzePattern(h);
      analysed = true;
    }
    double shift = 0.0;
    for (int attempt = 0; attempt < 8; ++attempt) {
      ldlt.setShift(shift);
      ldlt.factorize(h);
      if (ldlt.info() == Eigen::Success && (ldlt.vectorD().array() > 0.0).all()) break;
      shift = shift == 0.0 ? 1e-10 * std::max(max_diag, 1e-30) : shift * 100.0;
    }
    step = -ldlt.solve(g);
    if (!step.allFinite()) break;

    const double e0 = result.energy, slope = g.dot(step);
    double alpha = 1.0;
    bool accepted = false;
    for (int ls = 0; ls < 40 && !accepted; ++ls, alpha *= 0.5) {
      trial = net.x;
      for (size_t p = 0; p < n; ++p)
        if (dof[p] >= 0)
          for (int r = 0; r < dims; ++r) trial[p][r] += alpha * step[dof[p] + r];
      const double e1 = energy_of(net, trial);
      const bool armijo = e1 <= e0 + 1e-4 * alpha * slope;
      // Near the solution the decrease is below the round-off of E: judge by the residual.
      const bool roundoff = e1 <= e0 + 1e-12 * std::fabs(e0) + 1e-300;
      std::vector<Vec3> f1;
      if (armijo || roundoff) {
        f1 = forces_at(net, trial);
        const double r1 = residual_of(net, f1);
        if (armijo || r1 < result.residual_mn) {
          net.x.swap(trial);
          f.swap(f1);
          result.residual_mn = r1;
          result.energy = e1;
          accepted = true;
        }
      }
    }
    result.iterations = it + 1;
    if (!accepted) break;
    if (result.residual_mn <= settings.tolerance_mn) {
      result.converged = true;
      break;
    }
  }
  return result;
}

}  // namespace phaco::reference
