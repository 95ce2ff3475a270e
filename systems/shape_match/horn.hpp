#pragma once
// The optimal rigid map of one fragment, rest → current (seed 002 §6.2, "absolute orientation").
//
//   centroids  â = Σ m a / Σ m,  b̂ = Σ m b / Σ m                              (§6.2.2)
//   offsets    α = a − â,  β = b − b̂,   cross-covariance S = Σ m α βᵀ
//   rotation   the unit quaternion q maximising Σ m β·R(q)α = qᵀ N q, i.e. the eigenvector of the
//              largest eigenvalue of the symmetric, traceless 4×4 matrix N (§6.2.3; the seed writes
//              N = Σ A_iᵀ B_i; Horn 1987 eq. 31 writes the same matrix from the entries of S)
//   translation t = b̂ − R â                                                   (eq. 2)
//
// Two ways to find that eigenvector: Eigen's dense SelfAdjointEigenSolver (all four pairs) and the
// characteristic quartic the seed mentions, λ⁴ + c2 λ² + c1 λ + c0 with c2 = −2‖S‖², c1 = −8 det S,
// c0 = det N, whose largest root is found by Newton from the upper bound (Σ m|α|² + Σ m|β|²)/2 and
// whose eigenvector is the largest column of adj(N − λ1 I) (Horn 1987 §4; Theobald 2005 "QCP").
// The adjugate vanishes when λ1 is a multiple root, so the quartic solver is only as good as its
// flag: it checks that its vector attains λ1 (Rayleigh quotient) and flags it otherwise.
//
// Beside it, Müller et al. 2005 (MHTG05): Apq = Σ m β αᵀ, R = U Vᵀ from its SVD, with or without
// the determinant check (flip the last singular vector when det(U Vᵀ) < 0); without it a coplanar
// or mirrored cloud comes back as a reflection.
//
// What is determined: λ1 − λ2 = 2(σ2 + sign(det S)·σ3) for the singular values σ1 ≥ σ2 ≥ σ3 of S.
// Coplanar clouds (σ3 = 0) keep a gap; one cell (S = 0) and collinear cells (σ2 = σ3 = 0) do not:
// the twist about the line is free and any unit vector of the top eigenspace is optimal. The
// result carries the relative gap (λ1 − λ2)/λ1 so callers can tell (systems/shape_match/
// shape_match.hpp resolves it continuously).
//
// Float and double: every function is a template over the solve scalar T (float, double) and the
// input scalar P (float, double), explicitly instantiated in horn.cpp. Reads spans; writes nothing.
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>
#include <span>

namespace phaco::shape_match {

template <class T>
using Vec3T = Eigen::Matrix<T, 3, 1>;
template <class T>
using Mat3T = Eigen::Matrix<T, 3, 3>;
template <class T>
using Mat4T = Eigen::Matrix<T, 4, 4>;
template <class T>
using Vec4T = Eigen::Matrix<T, 4, 1>;

// How the top eigenvector of N is found.
enum class Solver : uint8_t {
  Eigen,    // Eigen::SelfAdjointEigenSolver<Matrix4> (tridiagonalisation + QR), all four pairs
  Quartic,  // Newton on the characteristic quartic, eigenvector from the adjugate
};

// Mass-weighted first and second moments of one fragment.
template <class T>
struct Moments {
  uint32_t count = 0;         // cells
  T mass = 0;                 // Σ m
  Vec3T<T> rest_centroid;     // â, mm
  Vec3T<T> current_centroid;  // b̂, mm
  Mat3T<T> cross;             // S = Σ m α βᵀ (rest offsets × current offsets), mass·mm²
  T rest_spread = 0;          // Σ m |α|²
  T current_spread = 0;       // Σ m |β|²
};

// Moments of the cells `ids` (all cells when ids is empty). masses empty = unit masses. One pass
// over the cells, about the first cell (so positions far from the origin do not cancel).
template <class T, class P>
Moments<T> fragment_moments(std::span<const Vec3T<P>> rest, std::span<const Vec3T<P>> current,
                            std::span<const P> masses, std::span<const uint32_t> ids = {});

// The raw sums behind fragment_moments, about fixed shift points, for reductions in chunks:
// accumulate cells [begin, end) of ids, merge chunks in a fixed order, finish.
template <class T>
struct MomentSums {
  uint32_t count = 0;
  T mass = 0;
  Vec3T<T> rest_sum = Vec3T<T>::Zero();     // Σ m (a − shift)
  Vec3T<T> current_sum = Vec3T<T>::Zero();  // Σ m (b − shift)
  Mat3T<T> cross = Mat3T<T>::Zero();        // Σ m (a − shift)(b − shift)ᵀ
  T rest_square = 0, current_square = 0;    // Σ m |a − shift|², Σ m |b − shift|²
};
template <class T, class P>
MomentSums<T> accumulate_moments(std::span<const Vec3T<P>> rest, std::span<const Vec3T<P>> current,
                                 std::span<const P> masses, std::span<const uint32_t> ids,
                                 uint32_t begin, uint32_t end, const Vec3T<T>& rest_shift,
                                 const Vec3T<T>& current_shift);
template <class T>
MomentSums<T> merge_sums(MomentSums<T> x, const MomentSums<T>& y);
template <class T>
Moments<T> finish_moments(const MomentSums<T>& sums, const Vec3T<T>& rest_shift,
                          const Vec3T<T>& current_shift);

// N of Horn 1987 (quaternion order w, x, y, z) from S.
template <class T>
Mat4T<T> horn_matrix(const Mat3T<T>& cross);

// Relative eigen-gap below which a solve cannot be trusted to pin the twist (measured in
// docs/shape_matching.md). Eigen's solver errs by about ε/gap: float 1e-2, double 1e-10. The
// quartic errs by about ε/gap² (its root's error ε/gap, amplified by the adjugate once more):
// float 1e-1, double 1e-5.
template <class T>
constexpr T kMinGap = sizeof(T) == 4 ? T(1e-2) : T(1e-10);
template <class T>
constexpr T kMinGapQuartic = sizeof(T) == 4 ? T(1e-1) : T(1e-5);

template <class T>
struct HornResult {
  Eigen::Quaternion<T> rotation = Eigen::Quaternion<T>::Identity();  // unit, w ≥ 0
  Vec3T<T> translation = Vec3T<T>::Zero();                           // t = b̂ − R â, mm
  Vec3T<T> rest_centroid = Vec3T<T>::Zero();
  Vec3T<T> current_centroid = Vec3T<T>::Zero();
  T top_eigenvalue = 0;  // λ1 = max Σ m β·Rα
  T gap = 0;             // (λ1 − λ2)/λ1, 0 when λ1 ≤ 0
  // The condition flag: gap below kMinGap<T> (Eigen) or kMinGapQuartic<T> (quartic), i.e. this
  // solve does not determine the rotation (one cell, two cells, collinear cells; or nearly so).
  bool ill_conditioned = true;
  // The second eigenvector (Solver::Eigen only; zero for Quartic): with `rotation` it spans the
  // optimal set when the top two eigenvalues coincide.
  Vec4T<T> second = Vec4T<T>::Zero();
};

// Solves from moments (the quaternion for S = 0 is the identity, flagged ill-conditioned).
template <class T>
HornResult<T> horn_solve(const Moments<T>& m, Solver solver = Solver::Eigen);

// Moments in T, then horn_solve.
template <class T, class P>
HornResult<T> horn(std::span<const Vec3T<P>> rest, std::span<const Vec3T<P>> current,
                   std::span<const P> masses, Solver solver = Solver::Eigen);

template <class T>
struct PolarResult {
  Mat3T<T> rotation = Mat3T<T>::Identity();  // U Vᵀ; a reflection (det −1) possible without check
  Vec3T<T> translation = Vec3T<T>::Zero();  // b̂ − R â
  T det = 1;                                // det(rotation), ±1
};

// MHTG05 polar decomposition of Apq by Eigen::JacobiSVD.
template <class T, class P>
PolarResult<T> polar(std::span<const Vec3T<P>> rest, std::span<const Vec3T<P>> current,
                     std::span<const P> masses, bool det_check);
template <class T>
PolarResult<T> polar_solve(const Moments<T>& m, bool det_check);

// Angle (rad, in [0, π]) of the rotation taking a to b.
template <class T>
T rotation_angle(const Eigen::Quaternion<T>& a, const Eigen::Quaternion<T>& b) {
  const Eigen::Quaternion<T> d = a.conjugate() * b;
  return T(2) * std::atan2(d.vec().norm(), std::abs(d.w()));
}

}  // namespace phaco::shape_match
