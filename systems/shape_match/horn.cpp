#include "systems/shape_match/horn.hpp"

#include <Eigen/Eigenvalues>
#include <Eigen/SVD>
#include <algorithm>
#include <cassert>
#include <cmath>
#include <limits>

#include "engine/core/invariants.hpp"

namespace phaco::shape_match {
namespace {

// Cell k of the fragment: ids[k] when ids is given, else k.
inline uint32_t cell_at(std::span<const uint32_t> ids, uint32_t k) {
  return ids.empty() ? k : ids[k];
}

// Below this share of the mean spread, λ1 counts as zero: nothing is determined (one cell, or all
// cells at one point).
template <class T>
constexpr T kNullScale = T(64) * std::numeric_limits<T>::epsilon();

template <class T>
T relative_gap(T top, T second, T scale) {
  if (!(top > kNullScale<T> * scale) || !(scale > T(0))) return T(0);
  return std::max(T(0), (top - second) / top);
}

template <class T>
HornResult<T> make_result(const Moments<T>& m, const Vec4T<T>& q_wxyz, T top, T second, T min_gap) {
  HornResult<T> r;
  Eigen::Quaternion<T> q(q_wxyz(0), q_wxyz(1), q_wxyz(2), q_wxyz(3));
  const T n = q.norm();
  if (n > T(0) && std::isfinite(n)) {
    q.coeffs() /= n;
  } else {
    q = Eigen::Quaternion<T>::Identity();
  }
  if (q.w() < T(0)) q.coeffs() = -q.coeffs();
  r.rotation = q;
  r.rest_centroid = m.rest_centroid;
  r.current_centroid = m.current_centroid;
  r.translation = m.current_centroid - q * m.rest_centroid;
  r.top_eigenvalue = top;
  r.gap = relative_gap(top, second, T(0.5) * (m.rest_spread + m.current_spread));
  r.ill_conditioned = !(r.gap >= min_gap);
  return r;
}

template <class T>
HornResult<T> solve_eigen(const Moments<T>& m) {
  const Mat4T<T> n = horn_matrix(m.cross);
  Eigen::SelfAdjointEigenSolver<Mat4T<T>> es(n, Eigen::ComputeEigenvectors);
  // Eigenvalues come in ascending order.
  HornResult<T> r = make_result<T>(m, es.eigenvectors().col(3), es.eigenvalues()(3),
                                   es.eigenvalues()(2), kMinGap<T>);
  r.second = es.eigenvectors().col(2);
  return r;
}

// adj(a) (= det(a)·a⁻¹) and det(a) of a 4×4 matrix from its 2×2 minors of rows 0–1 and 2–3
// (Laplace expansion by complementary minors): ~100 multiplications for all sixteen cofactors.
template <class T>
T adjugate4(const Mat4T<T>& a, Mat4T<T>& adj) {
  const T s0 = a(0, 0) * a(1, 1) - a(1, 0) * a(0, 1), s1 = a(0, 0) * a(1, 2) - a(1, 0) * a(0, 2);
  const T s2 = a(0, 0) * a(1, 3) - a(1, 0) * a(0, 3), s3 = a(0, 1) * a(1, 2) - a(1, 1) * a(0, 2);
  const T s4 = a(0, 1) * a(1, 3) - a(1, 1) * a(0, 3), s5 = a(0, 2) * a(1, 3) - a(1, 2) * a(0, 3);
  const T c5 = a(2, 2) * a(3, 3) - a(3, 2) * a(2, 3), c4 = a(2, 1) * a(3, 3) - a(3, 1) * a(2, 3);
  const T c3 = a(2, 1) * a(3, 2) - a(3, 1) * a(2, 2), c2 = a(2, 0) * a(3, 3) - a(3, 0) * a(2, 3);
  const T c1 = a(2, 0) * a(3, 2) - a(3, 0) * a(2, 2), c0 = a(2, 0) * a(3, 1) - a(3, 0) * a(2, 1);
  adj(0, 0) = a(1, 1) * c5 - a(1, 2) * c4 + a(1, 3) * c3;
  adj(0, 1) = -a(0, 1) * c5 + a(0, 2) * c4 - a(0, 3) * c3;
  adj(0, 2) = a(3, 1) * s5 - a(3, 2) * s4 + a(3, 3) * s3;
  adj(0, 3) = -a(2, 1) * s5 + a(2, 2) * s4 - a(2, 3) * s3;
  adj(1, 0) = -a(1, 0) * c5 + a(1, 2) * c2 - a(1, 3) * c1;
  adj(1, 1) = a(0, 0) * c5 - a(0, 2) * c2 + a(0, 3) * c1;
  adj(1, 2) = -a(3, 0) * s5 + a(3, 2) * s2 - a(3, 3) * s1;
  adj(1, 3) = a(2, 0) * s5 - a(2, 2) * s2 + a(2, 3) * s1;
  adj(2, 0) = a(1, 0) * c4 - a(1, 1) * c2 + a(1, 3) * c0;
  adj(2, 1) = -a(0, 0) * c4 + a(0, 1) * c2 - a(0, 3) * c0;
  adj(2, 2) = a(3, 0) * s4 - a(3, 1) * s2 + a(3, 3) * s0;
  adj(2, 3) = -a(2, 0) * s4 + a(2, 1) * s2 - a(2, 3) * s0;
  adj(3, 0) = -a(1, 0) * c3 + a(1, 1) * c1 - a(1, 2) * c0;
  adj(3, 1) = a(0, 0) * c3 - a(0, 1) * c1 + a(0, 2) * c0;
  adj(3, 2) = -a(3, 0) * s3 + a(3, 1) * s1 - a(3, 2) * s0;
  adj(3, 3) = a(2, 0) * s3 - a(2, 1) * s1 + a(2, 2) * s0;
  return s0 * c5 - s1 * c4 + s2 * c3 + s3 * c2 - s4 * c1 + s5 * c0;
}

template <class T>
HornResult<T> solve_quartic(const Moments<T>& m) {
  constexpr T kEps = std::numeric_limits<T>::epsilon();
  constexpr int kMaxNewton = 60;
  const Mat4T<T> n = horn_matrix(m.cross);
  const T c2 = T(-2) * m.cross.squaredNorm();
  const T c1 = T(-8) * m.cross.determinant();
  Mat4T<T> adj;
  const T c0 = adjugate4(n, adj);
  // Largest root: Newton from an upper bound (Σ m β·Rα ≤ Σ m|α||β| ≤ (Σ m|α|² + Σ m|β|²)/2); all
  // four roots are real, so from above Newton decreases monotonically onto λ1.
  const T scale = T(0.5) * (m.rest_spread + m.current_spread);
  T top = scale;
  for (int it = 0; it < kMaxNewton; ++it) {
    const T t2 = top * top;
    const T p = (t2 + c2) * t2 + c1 * top + c0;
    const T dp = (T(4) * t2 + T(2) * c2) * top + c1;
    if (!(dp > T(0))) break;
    const T step = p / dp;
    top -= step;
    if (std::abs(step) <= T(4) * kEps * scale) break;
  }
  // Second root: the deflated cubic x³ + λ1 x² + (λ1² + c2) x + (λ1³ + c2 λ1 + c1), Newton from λ1
  // downward, stopped once the gap is known to about 1 %.
  T second = top;
  {
    const T b = top * top + c2;
    const T c = (top * top + c2) * top + c1;
    for (int it = 0; it < kMaxNewton; ++it) {
      const T q = ((second + top) * second + b) * second + c;
      const T dq = (T(3) * second + T(2) * top) * second + b;
      if (!(q > T(0)) || !(dq > T(0))) break;
      const T step = q / dq;
      second -= step;
      if (step <= T(0.01) * (top - second) + T(4) * kEps * scale) break;
    }
  }
  // adj(N − λ1 I) = Π_{j>1}(λj − λ1) e1 e1ᵀ: its largest column is the best-conditioned copy of e1.
  Mat4T<T> a = n;
  a.diagonal().array() -= top;
  adjugate4(a, adj);
  Vec4T<T> best = adj.col(0);
  T best_norm = best.squaredNorm();
  for (int col = 1; col < 4; ++col) {
    const T nn = adj.col(col).squaredNorm();
    if (nn > best_norm) best_norm = nn, best = adj.col(col);
  }
  if (!(best_norm > T(0))) best = Vec4T<T>(1, 0, 0, 0);
  HornResult<T> r = make_result<T>(m, best, top, second, kMinGapQuartic<T>);
  // When λ1 is a multiple root, adj(N − λ1 I) vanishes and its columns are rounding noise that the
  // deflated gap (itself inaccurate there) may not reveal. The Rayleigh quotient does: a true top
  // eigenvector attains λ1 to rounding, noise does not.
  const Vec4T<T> q(r.rotation.w(), r.rotation.x(), r.rotation.y(), r.rotation.z());
  if (top - q.dot(n * q) > T(256) * kEps * scale) {
    r.gap = T(0);
    r.ill_conditioned = true;
  }
  return r;
}

}  // namespace

template <class T, class P>
MomentSums<T> accumulate_moments(std::span<const Vec3T<P>> rest, std::span<const Vec3T<P>> current,
                                 std::span<const P> masses, std::span<const uint32_t> ids,
                                 uint32_t begin, uint32_t end, const Vec3T<T>& rest_shift,
                                 const Vec3T<T>& current_shift) {
  // Positions (and masses) indexed alike; the chunk's cell ids within them.
  assert(same_size(rest, current) && (masses.empty() || same_size(rest, masses)));
  assert(begin <= end &&
         (ids.empty()
              ? end <= rest.size()
              : end <= ids.size() && all_below(ids.subspan(begin, end - begin), rest.size())));
  MomentSums<T> s;
  s.count = end - begin;
  for (uint32_t k = begin; k < end; ++k) {
    const uint32_t i = cell_at(ids, k);
    const T w = masses.empty() ? T(1) : static_cast<T>(masses[i]);
    const Vec3T<T> a = rest[i].template cast<T>() - rest_shift;
    const Vec3T<T> b = current[i].template cast<T>() - current_shift;
    const Vec3T<T> wa = w * a;
    s.mass += w;
    s.rest_sum += wa;
    s.current_sum += w * b;
    s.cross.noalias() += wa * b.transpose();
    s.rest_square += wa.dot(a);
    s.current_square += w * b.squaredNorm();
  }
  return s;
}

template <class T>
MomentSums<T> merge_sums(MomentSums<T> x, const MomentSums<T>& y) {
  x.count += y.count;
  x.mass += y.mass;
  x.rest_sum += y.rest_sum;
  x.current_sum += y.current_sum;
  x.cross += y.cross;
  x.rest_square += y.rest_square;
  x.current_square += y.current_square;
  return x;
}

template <class T>
Moments<T> finish_moments(const MomentSums<T>& s, const Vec3T<T>& rest_shift,
                          const Vec3T<T>& current_shift) {
  Moments<T> m;
  m.count = s.count;
  m.mass = s.mass;
  m.cross.setZero();
  m.rest_centroid = rest_shift;
  m.current_centroid = current_shift;
  if (!(s.mass > T(0))) return m;
  const Vec3T<T> ca = s.rest_sum / s.mass, cb = s.current_sum / s.mass;
  m.rest_centroid += ca;
  m.current_centroid += cb;
  // Σ w (a − â)(b − b̂)ᵀ = Σ w a bᵀ − M ĉa ĉbᵀ about the shift; the shift is a cell of the
  // fragment, so both terms are of the fragment's size and nothing cancels catastrophically.
  m.cross = s.cross - (s.mass * ca) * cb.transpose();
  m.rest_spread = std::max(T(0), s.rest_square - s.mass * ca.squaredNorm());
  m.current_spread = std::max(T(0), s.current_square - s.mass * cb.squaredNorm());
  return m;
}

template <class T, class P>
Moments<T> fragment_moments(std::span<const Vec3T<P>> rest, std::span<const Vec3T<P>> current,
                            std::span<const P> masses, std::span<const uint32_t> ids) {
  const auto n = static_cast<uint32_t>(ids.empty() ? rest.size() : ids.size());
  if (n == 0) return finish_moments<T>({}, Vec3T<T>::Zero(), Vec3T<T>::Zero());
  const Vec3T<T> rs = rest[cell_at(ids, 0)].template cast<T>();
  const Vec3T<T> cs = current[cell_at(ids, 0)].template cast<T>();
  return finish_moments(accumulate_moments<T, P>(rest, current, masses, ids, 0, n, rs, cs), rs, cs);
}

template <class T>
Mat4T<T> horn_matrix(const Mat3T<T>& s) {
  const T sxx = s(0, 0), sxy = s(0, 1), sxz = s(0, 2);
  const T syx = s(1, 0), syy = s(1, 1), syz = s(1, 2);
  const T szx = s(2, 0), szy = s(2, 1), szz = s(2, 2);
  Mat4T<T> n;
  n << sxx + syy + szz, syz - szy, szx - sxz, sxy - syx,  //
      syz - szy, sxx - syy - szz, sxy + syx, szx + sxz,   //
      szx - sxz, sxy + syx, -sxx + syy - szz, syz + szy,  //
      sxy - syx, szx + sxz, syz + szy, -sxx - syy + szz;
  return n;
}

template <class T>
HornResult<T> horn_solve(const Moments<T>& m, Solver solver) {
  return solver == Solver::Quartic ? solve_quartic(m) : solve_eigen(m);
}

template <class T, class P>
HornResult<T> horn(std::span<const Vec3T<P>> rest, std::span<const Vec3T<P>> current,
                   std::span<const P> masses, Solver solver) {
  return horn_solve(fragment_moments<T, P>(rest, current, masses), solver);
}

template <class T>
PolarResult<T> polar_solve(const Moments<T>& m, bool det_check) {
  // Apq = Σ m β αᵀ = Sᵀ.
  const Mat3T<T> apq = m.cross.transpose();
  Eigen::JacobiSVD<Mat3T<T>> svd(apq, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Mat3T<T> u = svd.matrixU();
  const Mat3T<T>& v = svd.matrixV();
  if (det_check && (u * v.transpose()).determinant() < T(0)) u.col(2) = -u.col(2);
  PolarResult<T> r;
  r.rotation = u * v.transpose();
  r.det = r.rotation.determinant();
  r.translation = m.current_centroid - r.rotation * m.rest_centroid;
  return r;
}

template <class T, class P>
PolarResult<T> polar(std::span<const Vec3T<P>> rest, std::span<const Vec3T<P>> current,
                     std::span<const P> masses, bool det_check) {
  return polar_solve(fragment_moments<T, P>(rest, current, masses), det_check);
}

#define PHACO_SHAPE_MATCH_INSTANTIATE(T, P)                                                        \
  template MomentSums<T> accumulate_moments<T, P>(                                                 \
      std::span<const Vec3T<P>>, std::span<const Vec3T<P>>, std::span<const P>,                    \
      std::span<const uint32_t>, uint32_t, uint32_t, const Vec3T<T>&, const Vec3T<T>&);            \
  template Moments<T> fragment_moments<T, P>(std::span<const Vec3T<P>>, std::span<const Vec3T<P>>, \
                                             std::span<const P>, std::span<const uint32_t>);       \
  template HornResult<T> horn<T, P>(std::span<const Vec3T<P>>, std::span<const Vec3T<P>>,          \
                                    std::span<const P>, Solver);                                   \
  template PolarResult<T> polar<T, P>(std::span<const Vec3T<P>>, std::span<const Vec3T<P>>,        \
                                      std::span<const P>, bool);

PHACO_SHAPE_MATCH_INSTANTIATE(float, float)
PHACO_SHAPE_MATCH_INSTANTIATE(float, double)
PHACO_SHAPE_MATCH_INSTANTIATE(double, float)
PHACO_SHAPE_MATCH_INSTANTIATE(double, double)
#undef PHACO_SHAPE_MATCH_INSTANTIATE

template MomentSums<float> merge_sums<float>(MomentSums<float>, const MomentSums<float>&);
template MomentSums<double> merge_sums<double>(MomentSums<double>, const MomentSums<double>&);
template Moments<float> finish_moments<float>(const MomentSums<float>&, const Vec3T<float>&,
                                              const Vec3T<float>&);
template Moments<double> finish_moments<double>(const MomentSums<double>&, const Vec3T<double>&,
                                                const Vec3T<double>&);
template Mat4T<float> horn_matrix<float>(const Mat3T<float>&);
template Mat4T<double> horn_matrix<double>(const Mat3T<double>&);
template HornResult<float> horn_solve<float>(const Moments<float>&, Solver);
template HornResult<double> horn_solve<double>(const Moments<double>&, Solver);
template PolarResult<float> polar_solve<float>(const Moments<float>&, bool);
template PolarResult<double> polar_solve<double>(const Moments<double>&, bool);

}  // namespace phaco::shape_match
