// Implicit Euler (Baraff & Witkin 1998) with Eigen's conjugate gradients; see implicit.hpp.
//
// Layout of the assembled operator: unknown u owns rows 3u..3u+2. Its neighbours (unknowns joined
// to it by a step spring, and u itself) form a sorted block row block_col[block_begin[u] ..
// block_begin[u+1]); scalar row 3u+a then stores 3·deg(u) entries starting at
// 9·block_begin[u] + 3·deg(u)·a, so the value of entry (3u+a, 3w+b) sits at
// row_start(3u+a) + 3·pos(w) + b. The pattern is written straight into Eigen's compressed arrays
// once per unknown set; each step only refills the values.
#include <Eigen/IterativeLinearSolvers>
#include <algorithm>
#include <cmath>

#include "systems/deform/implicit.hpp"

namespace phaco::deform::implicit_detail {
class SpringOperator;
}  // namespace phaco::deform::implicit_detail

template <>
struct Eigen::internal::traits<phaco::deform::implicit_detail::SpringOperator>
    : public Eigen::internal::traits<Eigen::SparseMatrix<double>> {};

namespace phaco::deform {

namespace implicit_detail {

// Matrix-free operator y = A·x over the cache's diagonal and spring blocks (Eigen's documented
// matrix-free pattern: an EigenBase with a custom GEMV product).
class SpringOperator : public Eigen::EigenBase<SpringOperator> {
 public:
  using Scalar = double;
  using RealScalar = double;
  using StorageIndex = int;
  enum { ColsAtCompileTime = Eigen::Dynamic, MaxColsAtCompileTime = Eigen::Dynamic, IsRowMajor = false };

  SpringOperator(const ImplicitCache& cache, double dt2)
      : cache_(&cache), dt2_(dt2), size_(static_cast<Eigen::Index>(3 * cache.unknowns.size())) {}
  Eigen::Index rows() const { return size_; }
  Eigen::Index cols() const { return size_; }

  template <class Rhs>
  Eigen::Product<SpringOperator, Rhs, Eigen::AliasFreeProduct> operator*(const Eigen::MatrixBase<Rhs>& x) const {
    return Eigen::Product<SpringOperator, Rhs, Eigen::AliasFreeProduct>(*this, x.derived());
  }

  // dst += alpha·A·x
  template <class Dst, class Rhs>
  void add_product(Dst& dst, const Rhs& x, double alpha) const {
    const ImplicitCache& c = *cache_;
    const size_t nu = c.unknowns.size();
    for (size_t u = 0; u < nu; ++u) {
      const Sym3& d = c.diag_block[u];
      const double x0 = x(3 * u), x1 = x(3 * u + 1), x2 = x(3 * u + 2);
      dst(3 * u) += alpha * (d[0] * x0 + d[1] * x1 + d[2] * x2);
      dst(3 * u + 1) += alpha * (d[1] * x0 + d[3] * x1 + d[4] * x2);
      dst(3 * u + 2) += alpha * (d[2] * x0 + d[4] * x1 + d[5] * x2);
    }
    const double s = -alpha * dt2_;
    for (size_t t = 0; t < c.step_springs.size(); ++t) {
      const uint32_t ui = c.spring_ui[t], uj = c.spring_uj[t];
      if (ui == kNotUnknown || uj == kNotUnknown) continue;
      const Sym3& k = c.spring_k[t];
      const double a0 = x(3 * uj), a1 = x(3 * uj + 1), a2 = x(3 * uj + 2);
      const double b0 = x(3 * ui), b1 = x(3 * ui + 1), b2 = x(3 * ui + 2);
      dst(3 * ui) += s * (k[0] * a0 + k[1] * a1 + k[2] * a2);
      dst(3 * ui + 1) += s * (k[1] * a0 + k[3] * a1 + k[4] * a2);
      dst(3 * ui + 2) += s * (k[2] * a0 + k[4] * a1 + k[5] * a2);
      dst(3 * uj) += s * (k[0] * b0 + k[1] * b1 + k[2] * b2);
      dst(3 * uj + 1) += s * (k[1] * b0 + k[3] * b1 + k[4] * b2);
      dst(3 * uj + 2) += s * (k[2] * b0 + k[4] * b1 + k[5] * b2);
    }
  }

 private:
  const ImplicitCache* cache_;
  double dt2_;
  Eigen::Index size_;
};

// Jacobi preconditioner whose inverse diagonal the step already computed while filling blocks.
class CachedJacobi {
 public:
  CachedJacobi() = default;
  template <class M>
  explicit CachedJacobi(const M&) {}
  template <class M>
  CachedJacobi& analyzePattern(const M&) { return *this; }
  template <class M>
  CachedJacobi& factorize(const M&) { return *this; }
  template <class M>
  CachedJacobi& compute(const M&) { return *this; }
  template <class Rhs>
  auto solve(const Eigen::MatrixBase<Rhs>& b) const { return inverse_->cwiseProduct(b.derived()); }
  Eigen::ComputationInfo info() const { return Eigen::Success; }
  void set(const Eigen::VectorXd* inverse) { inverse_ = inverse; }

 private:
  const Eigen::VectorXd* inverse_ = nullptr;
};

}  // namespace implicit_detail
}  // namespace phaco::deform

namespace Eigen::internal {

template <class Rhs>
struct generic_product_impl<phaco::deform::implicit_detail::SpringOperator, Rhs, SparseShape, DenseShape, GemvProduct>
    : generic_product_impl_base<phaco::deform::implicit_detail::SpringOperator, Rhs,
                                generic_product_impl<phaco::deform::implicit_detail::SpringOperator, Rhs>> {
  template <class Dest>
  static void scaleAndAddTo(Dest& dst, const phaco::deform::implicit_detail::SpringOperator& lhs, const Rhs& rhs,
                            const double& alpha) {
    lhs.add_product(dst, rhs, alpha);
  }
};

}  // namespace Eigen::internal

namespace phaco::deform {

SpringForceJacobian spring_force_jacobian(double dx, double dy, double dz, double rest_length, double stiffness,
                                          SpringLaw law) {
  SpringForceJacobian r;
  const double l = std::sqrt(dx * dx + dy * dy + dz * dz);
  if (!(l > 0.0)) return r;  // coincident ends: no direction, no force, no stiffness
  const double ux = dx / l, uy = dy / l, uz = dz / l;
  const double ext = l - rest_length;
  const double force = law == SpringLaw::Linear ? stiffness * ext : stiffness * ext * std::fabs(ext);
  const double axial = law == SpringLaw::Linear ? stiffness : 2.0 * stiffness * std::fabs(ext);
  const double transverse = std::max(force / l, 0.0);  // clamped under compression: stays PSD
  const double a = axial - transverse;
  r.force_on_i = {force * ux, force * uy, force * uz};
  r.k = {a * ux * ux + transverse, a * ux * uy, a * ux * uz, a * uy * uy + transverse, a * uy * uz,
         a * uz * uz + transverse};
  return r;
}

namespace {

using implicit_detail::CachedJacobi;
using implicit_detail::SpringOperator;

bool is_unknown_kind(const Particles& p, uint32_t i) {
  return p.slots.alive(i) && p.kind[i] == ParticleKind::Free && p.inv_mass[i] > 0.0f;
}

uint32_t find_in_row(const ImplicitCache& c, uint32_t u, uint32_t w) {
  const auto begin = c.block_col.begin() + c.block_begin[u], end = c.block_col.begin() + c.block_begin[u + 1];
  return static_cast<uint32_t>(std::lower_bound(begin, end, w) - begin);
}

// Selects unknowns and springs; returns true when they differ from the last step's.
bool select_unknowns(const Membrane& m, ImplicitCache& c) {
  const Particles& p = m.particles;
  const Springs& s = m.springs;
  const uint32_t n = p.slots.size();
  c.candidate_unknowns.clear();
  if (m.active.empty()) {
    for (uint32_t i = 0; i < n; ++i)
      if (is_unknown_kind(p, i)) c.candidate_unknowns.push_back(i);
  } else {
    for (uint32_t i : m.active)
      if (i < n && is_unknown_kind(p, i)) c.candidate_unknowns.push_back(i);
  }
  bool changed = !c.pattern_valid || c.pattern_operator != c.settings.cg_operator;
  if (c.candidate_unknowns != c.unknowns) {
    for (uint32_t i : c.unknowns) c.unknown_of[i] = kNotUnknown;
    c.unknowns.swap(c.candidate_unknowns);
    for (uint32_t u = 0; u < c.unknowns.size(); ++u) c.unknown_of[c.unknowns[u]] = u;
    changed = true;
  }
  c.candidate_springs.clear();
  auto consider = [&](uint32_t e) {
    if (s.slots.alive(e) && (c.unknown_of[s.i[e]] != kNotUnknown || c.unknown_of[s.j[e]] != kNotUnknown))
      c.candidate_springs.push_back(e);
  };
  if (m.active.empty()) {
    for (uint32_t e = 0; e < s.slots.size(); ++e) consider(e);
  } else {
    for (uint32_t e : m.active_springs)
      if (e < s.slots.size()) consider(e);
  }
  if (c.candidate_springs != c.step_springs) {
    c.step_springs.swap(c.candidate_springs);
    changed = true;
  }
  return changed;
}

void build_pattern(const Springs& s, ImplicitCache& c) {
  const uint32_t nu = static_cast<uint32_t>(c.unknowns.size());
  const size_t ns = c.step_springs.size();
  c.spring_ui.resize(ns);
  c.spring_uj.resize(ns);
  c.block_begin.assign(nu + 1, 0);
  for (uint32_t u = 0; u < nu; ++u) c.block_begin[u + 1] = 1;  // the diagonal block
  for (size_t t = 0; t < ns; ++t) {
    const uint32_t e = c.step_springs[t];
    const uint32_t ui = c.unknown_of[s.i[e]], uj = c.unknown_of[s.j[e]];
    c.spring_ui[t] = ui, c.spring_uj[t] = uj;
    if (ui != kNotUnknown && uj != kNotUnknown) ++c.block_begin[ui + 1], ++c.block_begin[uj + 1];
  }
  for (uint32_t u = 0; u < nu; ++u) c.block_begin[u + 1] += c.block_begin[u];
  c.block_col.resize(c.block_begin[nu]);
  c.diag_pos.resize(nu);
  {
    std::vector<uint32_t>& fill = c.candidate_unknowns;  // free scratch at this point
    fill.assign(c.block_begin.begin(), c.block_begin.end() - 1);
    for (uint32_t u = 0; u < nu; ++u) c.block_col[fill[u]++] = u;
    for (size_t t = 0; t < ns; ++t) {
      const uint32_t ui = c.spring_ui[t], uj = c.spring_uj[t];
      if (ui == kNotUnknown || uj == kNotUnknown) continue;
      c.block_col[fill[ui]++] = uj;
      c.block_col[fill[uj]++] = ui;
    }
  }
  for (uint32_t u = 0; u < nu; ++u) {
    std::sort(c.block_col.begin() + c.block_begin[u], c.block_col.begin() + c.block_begin[u + 1]);
    c.diag_pos[u] = find_in_row(c, u, u);
  }
  c.spring_pos_ij.resize(ns);
  c.spring_pos_ji.resize(ns);
  for (size_t t = 0; t < ns; ++t) {
    const uint32_t ui = c.spring_ui[t], uj = c.spring_uj[t];
    const bool both = ui != kNotUnknown && uj != kNotUnknown;
    c.spring_pos_ij[t] = both ? find_in_row(c, ui, uj) : kNotUnknown;
    c.spring_pos_ji[t] = both ? find_in_row(c, uj, ui) : kNotUnknown;
  }

  if (c.settings.cg_operator == CgOperator::Assembled) {
    const int rows = static_cast<int>(3 * nu);
    c.matrix.resize(rows, rows);
    c.matrix.resizeNonZeros(static_cast<Eigen::Index>(9) * c.block_begin[nu]);
    int* outer = c.matrix.outerIndexPtr();
    int* inner = c.matrix.innerIndexPtr();
    int k = 0;
    for (uint32_t u = 0; u < nu; ++u) {
      for (int a = 0; a < 3; ++a) {
        outer[3 * u + a] = k;
        for (uint32_t b = c.block_begin[u]; b < c.block_begin[u + 1]; ++b)
          for (int d = 0; d < 3; ++d) inner[k++] = static_cast<int>(3 * c.block_col[b]) + d;
      }
    }
    outer[rows] = k;
  }
  c.pattern_valid = true;
  c.pattern_operator = c.settings.cg_operator;
  ++c.stats.pattern_builds;
}

inline void add_sym(Sym3& to, const Sym3& k, double s) {
  for (int q = 0; q < 6; ++q) to[q] += s * k[q];
}

inline double sym_at(const Sym3& k, int a, int b) {
  static constexpr int kIndex[3][3] = {{0, 1, 2}, {1, 3, 4}, {2, 4, 5}};
  return k[kIndex[a][b]];
}

// Forces, right side and blocks of the step's system.
void assemble(const Membrane& m, double dt, ImplicitCache& c) {
  const Particles& p = m.particles;
  const Springs& s = m.springs;
  const Dynamics& dyn = m.dynamics;
  const size_t nu = c.unknowns.size(), ns = c.step_springs.size();
  const double dt2 = dt * dt;
  const double drag = double(dyn.damping_per_s) + dyn.viscosity_per_s;
  const bool glued = m.glue && m.glue->x.size() == p.slots.size();
  const double glue_k = glued ? dyn.glue_stiffness_mn_mm : 0.0;
  c.force.resize(3 * nu);
  c.rhs.resize(3 * nu);  // accumulates ∂f/∂x·v first
  c.diag_block.resize(nu);
  c.spring_k.resize(ns);
  for (size_t u = 0; u < nu; ++u) {
    const uint32_t i = c.unknowns[u];
    // Mass scaling changes inertia only: the weight stays that of the true mass (docs/dynamics.md).
    const double true_mass = 1.0 / p.inv_mass[i];
    const double mass = implicit_detail::mass_scale(dyn) * true_mass;
    const double v[3] = {p.vx[i], p.vy[i], p.vz[i]};
    const double x[3] = {p.x[i], p.y[i], p.z[i]};
    for (int a = 0; a < 3; ++a) {
      const double rest = glued ? (a == 0 ? m.glue->x[i] : a == 1 ? m.glue->y[i] : m.glue->z[i]) : x[a];
      c.force[3 * u + a] = true_mass * dyn.gravity_mm_s2[a] - mass * drag * v[a] - glue_k * (x[a] - rest);
      c.rhs[3 * u + a] = -glue_k * v[a];
    }
    const double d = mass * (1.0 + dt * drag) + dt2 * glue_k;
    c.diag_block[u] = {d, 0.0, 0.0, d, 0.0, d};
  }
  implicit_detail::add_point_loads(m, c.unknown_of, c.force.data());
  for (size_t t = 0; t < ns; ++t) {
    const uint32_t e = c.step_springs[t], i = s.i[e], j = s.j[e];
    const SpringForceJacobian sj =
        spring_force_jacobian(double(p.x[j]) - p.x[i], double(p.y[j]) - p.y[i], double(p.z[j]) - p.z[i],
                              s.rest_length[e], s.stiffness[e], dyn.law);
    c.spring_k[t] = sj.k;
    const uint32_t ui = c.spring_ui[t], uj = c.spring_uj[t];
    // A fixed end does not move during the step (a scripted one was already put at its
    // end-of-frame position by the tool): it brings no velocity term.
    double vi[3] = {0.0, 0.0, 0.0}, vj[3] = {0.0, 0.0, 0.0};
    if (ui != kNotUnknown) vi[0] = p.vx[i], vi[1] = p.vy[i], vi[2] = p.vz[i];
    if (uj != kNotUnknown) vj[0] = p.vx[j], vj[1] = p.vy[j], vj[2] = p.vz[j];
    const double w[3] = {vj[0] - vi[0], vj[1] - vi[1], vj[2] - vi[2]};
    const Sym3& k = sj.k;
    const double kw[3] = {k[0] * w[0] + k[1] * w[1] + k[2] * w[2], k[1] * w[0] + k[3] * w[1] + k[4] * w[2],
                          k[2] * w[0] + k[4] * w[1] + k[5] * w[2]};
    if (ui != kNotUnknown) {
      for (int a = 0; a < 3; ++a) c.force[3 * ui + a] += sj.force_on_i[a], c.rhs[3 * ui + a] += kw[a];
      add_sym(c.diag_block[ui], k, dt2);
    }
    if (uj != kNotUnknown) {
      for (int a = 0; a < 3; ++a) c.force[3 * uj + a] -= sj.force_on_i[a], c.rhs[3 * uj + a] -= kw[a];
      add_sym(c.diag_block[uj], k, dt2);
    }
  }
  c.rhs = dt * c.force + dt2 * c.rhs;
  c.inverse_diagonal.resize(3 * nu);
  for (size_t u = 0; u < nu; ++u) {
    const Sym3& d = c.diag_block[u];
    c.inverse_diagonal[3 * u] = 1.0 / d[0], c.inverse_diagonal[3 * u + 1] = 1.0 / d[3];
    c.inverse_diagonal[3 * u + 2] = 1.0 / d[5];
  }

  if (c.settings.cg_operator != CgOperator::Assembled) return;
  double* val = c.matrix.valuePtr();
  const int* outer = c.matrix.outerIndexPtr();
  std::fill(val, val + c.matrix.nonZeros(), 0.0);
  for (size_t u = 0; u < nu; ++u)
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < 3; ++b) val[outer[3 * u + a] + 3 * c.diag_pos[u] + b] = sym_at(c.diag_block[u], a, b);
  for (size_t t = 0; t < ns; ++t) {
    const uint32_t ui = c.spring_ui[t], uj = c.spring_uj[t];
    if (ui == kNotUnknown || uj == kNotUnknown) continue;
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < 3; ++b) {
        const double kab = -dt2 * sym_at(c.spring_k[t], a, b);
        val[outer[3 * ui + a] + 3 * c.spring_pos_ij[t] + b] += kab;
        val[outer[3 * uj + a] + 3 * c.spring_pos_ji[t] + b] += kab;
      }
  }
}

template <class Operator>
void solve(const Operator& op, ImplicitCache& c) {
  Eigen::ConjugateGradient<Operator, Eigen::Lower | Eigen::Upper, CachedJacobi> cg;
  cg.preconditioner().set(&c.inverse_diagonal);
  cg.setTolerance(c.settings.cg_tolerance);
  cg.setMaxIterations(std::max(c.settings.cg_max_iterations, 1));
  cg.compute(op);
  c.dv = cg.solveWithGuess(c.rhs, c.guess);
  c.stats.cg_iterations = static_cast<int>(cg.iterations());
  c.stats.cg_residual = cg.error();
  c.stats.cg_converged = cg.info() == Eigen::Success;
}

}  // namespace

void implicit_euler_step(Membrane& m, double dt, ImplicitCache& c) {
  Particles& p = m.particles;
  const uint32_t n = p.slots.size();
  if (c.unknown_of.size() != n) {
    c.unknown_of.assign(n, kNotUnknown);
    c.warm_dv.assign(3 * size_t(n), 0.0);
    c.unknowns.clear();
    c.pattern_valid = false;
  }
  if (select_unknowns(m, c)) build_pattern(m.springs, c);
  const size_t nu = c.unknowns.size();
  ++c.stats.steps;
  c.stats.unknowns = static_cast<uint32_t>(nu);
  c.stats.springs = static_cast<uint32_t>(c.step_springs.size());
  c.stats.nonzeros = 9 * uint64_t(c.block_begin.empty() ? 0 : c.block_begin.back());
  if (nu == 0) {
    c.stats.cg_iterations = 0, c.stats.cg_residual = 0.0, c.stats.cg_converged = true;
    return;
  }
  assemble(m, dt, c);

  c.guess.resize(3 * nu);
  for (size_t u = 0; u < nu; ++u)
    for (int a = 0; a < 3; ++a) c.guess[3 * u + a] = c.settings.warm_start ? c.warm_dv[3 * c.unknowns[u] + a] : 0.0;
  if (c.settings.cg_operator == CgOperator::Assembled) solve(c.matrix, c);
  else solve(SpringOperator(c, dt * dt), c);
  c.stats.cg_iterations_total += c.stats.cg_iterations;

  // Line search on the incremental potential along Δx = dt·(v + Δv).
  c.step_dx.resize(3 * nu);
  for (size_t u = 0; u < nu; ++u) {
    const uint32_t i = c.unknowns[u];
    c.step_dx[3 * u] = dt * (p.vx[i] + c.dv[3 * u]);
    c.step_dx[3 * u + 1] = dt * (p.vy[i] + c.dv[3 * u + 1]);
    c.step_dx[3 * u + 2] = dt * (p.vz[i] + c.dv[3 * u + 2]);
  }
  const double alpha = implicit_detail::line_search(m, dt, c.settings.max_line_search_halvings, c.unknowns,
                                                    c.unknown_of, c.step_springs, c.step_dx.data());
  c.stats.step_fraction = alpha;
  if (alpha < 1.0) ++c.stats.line_search_cuts;

  if (m.forces.fx.size() != n) m.forces.resize_zero(n);
  for (size_t u = 0; u < nu; ++u) {
    const uint32_t i = c.unknowns[u];
    const double dx = alpha * c.step_dx[3 * u], dy = alpha * c.step_dx[3 * u + 1], dz = alpha * c.step_dx[3 * u + 2];
    for (int a = 0; a < 3; ++a) {
      const double v_old = a == 0 ? p.vx[i] : a == 1 ? p.vy[i] : p.vz[i];
      c.warm_dv[3 * i + a] = alpha * c.step_dx[3 * u + a] / dt - v_old;
    }
    p.vx[i] = static_cast<float>(dx / dt), p.vy[i] = static_cast<float>(dy / dt), p.vz[i] = static_cast<float>(dz / dt);
    p.x[i] = static_cast<float>(p.x[i] + dx);
    p.y[i] = static_cast<float>(p.y[i] + dy);
    p.z[i] = static_cast<float>(p.z[i] + dz);
    m.forces.fx[i] = static_cast<float>(c.force[3 * u]);
    m.forces.fy[i] = static_cast<float>(c.force[3 * u + 1]);
    m.forces.fz[i] = static_cast<float>(c.force[3 * u + 2]);
  }
}

}  // namespace phaco::deform
