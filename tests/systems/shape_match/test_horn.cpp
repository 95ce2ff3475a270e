// Horn's closed form and MHTG05's polar decomposition (systems/shape_match/horn.hpp): recovery of
// random rigid transforms, proper rotations on every degenerate cloud, the mirror images of polar
// decomposition without its determinant check, and float failing where double holds.
#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <cmath>
#include <span>
#include <vector>

#include "systems/shape_match/horn.hpp"
#include "tests/systems/shape_match/clouds.hpp"

namespace phaco::shape_match {
namespace {

using test::Gen;

template <class T>
std::span<const Vec3T<T>> cs(const std::vector<Vec3T<T>>& v) {
  return {v.data(), v.size()};
}
template <class T>
std::span<const T> cs(const std::vector<T>& v) {
  return {v.data(), v.size()};
}

std::vector<Vec3f> to_float(const std::vector<Vec3>& v) {
  std::vector<Vec3f> out(v.size());
  for (size_t i = 0; i < v.size(); ++i) out[i] = v[i].cast<float>();
  return out;
}

// σ2/σ1 of the centred cloud: how far from collinear it is.
double spread_ratio(const std::vector<Vec3>& p) {
  Vec3 c = Vec3::Zero();
  for (const Vec3& x : p) c += x;
  c /= static_cast<double>(p.size());
  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
  for (const Vec3& x : p) cov += (x - c) * (x - c).transpose();
  const Eigen::Vector3d ev = Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(cov).eigenvalues();
  return ev(2) > 0 ? std::sqrt(std::max(ev(1), 0.0) / ev(2)) : 0;
}

// qᵀ N q equals Σ m β·R(q)α for any unit q: N is built in the orientation the solver assumes.
TEST(Horn, MatrixIsTheQuadraticFormOfTheAlignment) {
  Gen g(11);
  for (int trial = 0; trial < 20; ++trial) {
    const auto a = test::random_cloud(g, 7);
    const auto b = test::random_cloud(g, 7, Vec3(-1, 0, 3));
    const auto m = test::random_masses(g, a.size());
    const Moments<double> mo = fragment_moments<double, double>(cs(a), cs(b), cs(m));
    const Mat4T<double> n = horn_matrix(mo.cross);
    EXPECT_NEAR(n.trace(), 0.0, 1e-12);
    EXPECT_LT((n - n.transpose()).norm(), 1e-14);
    const Quat q = g.rotation();
    const Vec4T<double> v(q.w(), q.x(), q.y(), q.z());
    double direct = 0;
    for (size_t i = 0; i < a.size(); ++i)
      direct += m[i] * (b[i] - mo.current_centroid).dot(q * (a[i] - mo.rest_centroid));
    EXPECT_NEAR(v.dot(n * v), direct, 1e-10 * (1 + std::abs(direct)));
  }
}

// Random rigid transforms of random clouds of 3..1000 points, noise-free, not near collinear:
// both solvers in double recover the rotation within 1e-5 rad and the translation.
TEST(Horn, RecoversRandomRigidTransforms) {
  Gen g(12);
  for (int n : {3, 4, 5, 8, 16, 64, 256, 1000}) {
    for (int trial = 0; trial < (n >= 256 ? 5 : 40); ++trial) {
      std::vector<Vec3> a = test::random_cloud(g, n);
      while (spread_ratio(a) < 0.05) a = test::random_cloud(g, n);
      const Quat r = g.rotation();
      const Vec3 t = g.in_box(5);
      const auto b = test::moved(a, r, t);
      const auto m = test::random_masses(g, a.size());
      for (Solver s : {Solver::Eigen, Solver::Quartic}) {
        const HornResult<double> h = horn<double, double>(cs(a), cs(b), cs(m), s);
        EXPECT_LT(rotation_angle(h.rotation, r), 1e-5) << "n=" << n << " solver=" << int(s);
        EXPECT_LT((h.translation - t).norm(), 1e-8);
        EXPECT_FALSE(h.ill_conditioned);
      }
    }
  }
}

// Coplanar clouds are determined (λ1 − λ2 = 2σ2 > 0): recovered within 1e-5 rad.
TEST(Horn, RecoversCoplanarClouds) {
  Gen g(13);
  for (int n : {3, 4, 10, 100}) {
    for (int trial = 0; trial < 30; ++trial) {
      std::vector<Vec3> a = test::coplanar_cloud(g, n);
      while (spread_ratio(a) < 0.05) a = test::coplanar_cloud(g, n);
      const Quat r = g.rotation();
      const auto b = test::moved(a, r, g.in_box(5));
      for (Solver s : {Solver::Eigen, Solver::Quartic}) {
        const HornResult<double> h = horn<double, double>(cs(a), cs(b), {}, s);
        EXPECT_LT(rotation_angle(h.rotation, r), 1e-5) << "n=" << n;
      }
    }
  }
}

// Every cloud, degenerate or not, float or double, either solver: a finite unit quaternion, i.e.
// a proper rotation (det +1).
TEST(Horn, AlwaysAProperRotation) {
  Gen g(14);
  std::vector<std::vector<Vec3>> rests;
  for (int n = 1; n <= 3; ++n) rests.push_back(test::random_cloud(g, n));
  rests.push_back(test::line_cloud(g, 3, 0.0));
  rests.push_back(test::line_cloud(g, 50, 0.0));
  rests.push_back(test::line_cloud(g, 5, 1e-4));
  rests.push_back(test::coplanar_cloud(g, 4));
  rests.push_back(test::coplanar_cloud(g, 200));
  rests.push_back(std::vector<Vec3>(6, Vec3(1, 2, 3)));  // all cells at one point
  rests.push_back(test::random_cloud(g, 1000));
  for (const auto& a : rests) {
    for (int variant = 0; variant < 3; ++variant) {
      std::vector<Vec3> b = test::moved(a, g.rotation(), g.in_box(3));
      if (variant == 1)
        for (Vec3& x : b) x += 0.05 * g.in_box(1);  // noisy
      if (variant == 2)
        for (Vec3& x : b) x.x() = -x.x();  // mirrored
      for (Solver s : {Solver::Eigen, Solver::Quartic}) {
        const HornResult<double> d = horn<double, double>(cs(a), cs(b), {}, s);
        EXPECT_NEAR(d.rotation.norm(), 1.0, 1e-12);
        EXPECT_NEAR(d.rotation.toRotationMatrix().determinant(), 1.0, 1e-12);
        EXPECT_TRUE(d.translation.allFinite());
        const auto af = to_float(a), bf = to_float(b);
        const HornResult<float> f = horn<float, float>(cs(af), cs(bf), {}, s);
        EXPECT_NEAR(f.rotation.norm(), 1.0f, 1e-5f);
        EXPECT_NEAR(f.rotation.toRotationMatrix().determinant(), 1.0f, 1e-4f);
        EXPECT_TRUE(f.translation.allFinite());
      }
    }
  }
}

// One cell, two cells, collinear cells: the top two eigenvalues coincide and the result says so.
TEST(Horn, FlagsTheUndeterminedTwist) {
  Gen g(15);
  std::vector<std::vector<Vec3>> clouds;
  for (int k = 0; k < 50; ++k) {
    clouds.push_back(test::random_cloud(g, 1 + k % 2));
    clouds.push_back(test::line_cloud(g, 3 + k, 0.0));
  }
  for (const auto& a : clouds) {
    const auto b = test::moved(a, g.rotation(), g.in_box(3));
    const HornResult<double> h = horn<double, double>(cs(a), cs(b), {});
    EXPECT_TRUE(h.ill_conditioned) << a.size();
    EXPECT_LT(h.gap, 1e-10);
    // The quartic solver's adjugate vanishes here; it must say so, in both precisions.
    EXPECT_TRUE((horn<double, double>(cs(a), cs(b), {}, Solver::Quartic).ill_conditioned));
    const auto af = to_float(a), bf = to_float(b);
    EXPECT_TRUE((horn<float, float>(cs(af), cs(bf), {}, Solver::Quartic).ill_conditioned));
    EXPECT_TRUE((horn<float, float>(cs(af), cs(bf), {}, Solver::Eigen).ill_conditioned));
    // The line's direction itself is still mapped right (collinear with ≥ 2 cells).
    if (a.size() >= 2) {
      const Vec3 da = (a[1] - a[0]).normalized(), db = (b[1] - b[0]).normalized();
      EXPECT_LT((h.rotation * da - db).norm(), 1e-9);
    }
  }
}

// Noisy clouds: Horn's rotation is optimal, so no nearby rotation has a smaller residual, and
// polar decomposition with the determinant check (which solves the same problem) agrees with it.
TEST(Horn, PolarWithDetCheckEqualsHornAndBothAreOptimal) {
  Gen g(16);
  for (int n : {3, 4, 8, 64, 500}) {
    for (int trial = 0; trial < 20; ++trial) {
      std::vector<Vec3> a = test::random_cloud(g, n);
      while (spread_ratio(a) < 0.05) a = test::random_cloud(g, n);
      auto b = test::moved(a, g.rotation(), g.in_box(5));
      for (Vec3& x : b) x += 0.1 * g.in_box(1);
      const auto m = test::random_masses(g, a.size());
      const HornResult<double> h = horn<double, double>(cs(a), cs(b), cs(m));
      const PolarResult<double> p = polar<double, double>(cs(a), cs(b), cs(m), true);
      EXPECT_LT(rotation_angle(h.rotation, Quat(p.rotation)), 1e-6) << "n=" << n;
      EXPECT_NEAR(p.det, 1.0, 1e-12);
      auto residual = [&](const Quat& q) {
        double e = 0;
        for (size_t i = 0; i < a.size(); ++i)
          e += m[i] * (b[i] - h.current_centroid - q * (a[i] - h.rest_centroid)).squaredNorm();
        return e;
      };
      const double best = residual(h.rotation);
      for (int k = 0; k < 6; ++k) {
        const Quat nudge(Eigen::AngleAxisd(1e-3, g.unit()));
        EXPECT_LE(best, residual(nudge * h.rotation) * (1 + 1e-12));
      }
    }
  }
}

// Without the determinant check, polar decomposition returns reflections: always for a mirrored
// cloud, and for some coplanar clouds (the third singular vector's sign is free). With it, never.
TEST(Horn, PolarWithoutDetCheckReturnsMirrorImages) {
  Gen g(17);
  const auto a = test::random_cloud(g, 10);
  auto b = test::moved(a, g.rotation(), g.in_box(2));
  for (Vec3& x : b) x.y() = -x.y();
  const std::span<const double> unit_mass;
  EXPECT_NEAR(polar<double>(cs(a), cs(b), unit_mass, false).det, -1.0, 1e-12);
  EXPECT_NEAR(polar<double>(cs(a), cs(b), unit_mass, true).det, 1.0, 1e-12);
  const HornResult<double> h = horn<double>(cs(a), cs(b), unit_mass);
  EXPECT_NEAR(h.rotation.toRotationMatrix().determinant(), 1.0, 1e-12);

  int mirrored = 0;
  for (int trial = 0; trial < 100; ++trial) {
    const auto c = test::coplanar_cloud(g, 5);
    const Quat r = g.rotation();
    const auto d = test::moved(c, r, g.in_box(2));
    const PolarResult<double> free = polar<double, double>(cs(c), cs(d), {}, false);
    const PolarResult<double> checked = polar<double, double>(cs(c), cs(d), {}, true);
    EXPECT_NEAR(checked.det, 1.0, 1e-12);
    EXPECT_NEAR(std::abs(free.det), 1.0, 1e-12);
    if (free.det < 0) {
      ++mirrored;
      // The mirror image still fits the plane's points exactly: it is an optimum of Apq's polar
      // problem, just not a rotation.
      for (size_t i = 0; i < c.size(); ++i)
        EXPECT_LT((free.rotation * c[i] + free.translation - d[i]).norm(), 1e-9);
    }
    EXPECT_LT(rotation_angle(Quat(checked.rotation), r), 1e-6);
  }
  EXPECT_GT(mirrored, 0) << "no coplanar cloud came back mirrored in 100 trials";
}

// The quartic solver agrees with Eigen's dense solver on well-conditioned clouds (float and
// double).
TEST(Horn, QuarticSolverEqualsEigenSolver) {
  Gen g(18);
  for (int n : {3, 4, 6, 20, 200}) {
    for (int trial = 0; trial < 30; ++trial) {
      std::vector<Vec3> a = test::random_cloud(g, n);
      while (spread_ratio(a) < 0.1) a = test::random_cloud(g, n);
      auto b = test::moved(a, g.rotation(), g.in_box(4));
      for (Vec3& x : b) x += 0.05 * g.in_box(1);
      const HornResult<double> e = horn<double, double>(cs(a), cs(b), {}, Solver::Eigen);
      const HornResult<double> q = horn<double, double>(cs(a), cs(b), {}, Solver::Quartic);
      EXPECT_LT(rotation_angle(e.rotation, q.rotation), 1e-9);
      EXPECT_NEAR(e.top_eigenvalue, q.top_eigenvalue, 1e-10 * e.top_eigenvalue);
      EXPECT_NEAR(e.gap, q.gap, 0.02 * e.gap);
      const auto af = to_float(a), bf = to_float(b);
      const HornResult<float> ef = horn<float, float>(cs(af), cs(bf), {}, Solver::Eigen);
      const HornResult<float> qf = horn<float, float>(cs(af), cs(bf), {}, Solver::Quartic);
      EXPECT_LT(rotation_angle(ef.rotation.cast<double>(), e.rotation), 1e-3);
      EXPECT_LT(rotation_angle(qf.rotation.cast<double>(), e.rotation), 1e-3);
    }
  }
}

// A nearly collinear cluster (cells 1e-4 mm off a 4 mm line): float cannot see the twist (its
// error is about ε_float/gap) and flags it; double recovers the rotation.
TEST(Horn, FloatFailsOnNearlyCollinearDoubleHolds) {
  Gen g(19);
  double worst_float = 0;
  for (int trial = 0; trial < 100; ++trial) {
    const auto a = test::line_cloud(g, 4, 1e-4);
    const Quat r = g.rotation();
    const auto b = test::moved(a, r, g.in_box(2));
    const HornResult<double> d = horn<double, double>(cs(a), cs(b), {});
    EXPECT_LT(rotation_angle(d.rotation, r), 1e-5);
    EXPECT_FALSE(d.ill_conditioned);
    // The quartic (error ε/gap²) cannot resolve it even in double, and says so.
    EXPECT_TRUE((horn<double, double>(cs(a), cs(b), {}, Solver::Quartic).ill_conditioned));
    const auto af = to_float(a), bf = to_float(b);
    const HornResult<float> f = horn<float, float>(cs(af), cs(bf), {});
    EXPECT_TRUE(f.ill_conditioned);
    worst_float = std::max(worst_float, rotation_angle(f.rotation.cast<double>(), r));
  }
  EXPECT_GT(worst_float * 180 / M_PI, 30.0) << "float was expected to miss the twist badly";
}

}  // namespace
}  // namespace phaco::shape_match
