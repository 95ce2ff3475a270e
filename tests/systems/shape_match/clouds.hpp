#pragma once
// Seeded point clouds and rigid transforms for the shape-matching tests (counter-based RNG, so the
// clouds are the same on every platform).
#include <cmath>
#include <cstdint>
#include <vector>

#include "engine/core/math.hpp"
#include "engine/core/rng.hpp"

namespace phaco::shape_match::test {

class Gen {
 public:
  explicit Gen(uint64_t seed) : rng_(seed, 5) {}
  double uniform(double lo, double hi) { return lo + (hi - lo) * rng_.uniform_double(0, n_++); }
  double normal() {
    const double u = std::max(uniform(0, 1), 1e-300), v = uniform(0, 1);
    return std::sqrt(-2 * std::log(u)) * std::cos(2 * M_PI * v);
  }
  Vec3 in_box(double h) { return {uniform(-h, h), uniform(-h, h), uniform(-h, h)}; }
  Vec3 unit() {
    const Vec3 v(normal(), normal(), normal());
    return v / v.norm();
  }
  // Uniform on SO(3) (Shoemake).
  Quat rotation() {
    const double u1 = uniform(0, 1), u2 = uniform(0, 2 * M_PI), u3 = uniform(0, 2 * M_PI);
    const double a = std::sqrt(1 - u1), b = std::sqrt(u1);
    return Quat(a * std::sin(u2), a * std::cos(u2), b * std::sin(u3), b * std::cos(u3))
        .normalized();
  }

 private:
  CounterRng rng_;
  uint32_t n_ = 0;
};

// n points in a 4 mm box around `centre`.
inline std::vector<Vec3> random_cloud(Gen& g, int n, const Vec3& centre = Vec3(1, -2, 0.5)) {
  std::vector<Vec3> p(n);
  for (auto& x : p) x = centre + g.in_box(2.0);
  return p;
}

// n points on a random plane through `centre`.
inline std::vector<Vec3> coplanar_cloud(Gen& g, int n, const Vec3& centre = Vec3(1, -2, 0.5)) {
  const Quat r = g.rotation();
  std::vector<Vec3> p(n);
  for (auto& x : p) x = centre + r * Vec3(g.uniform(-2, 2), g.uniform(-2, 2), 0);
  return p;
}

// n points along a random line, each pushed off it by up to `offset` mm (0: exactly collinear).
inline std::vector<Vec3> line_cloud(Gen& g, int n, double offset,
                                    const Vec3& centre = Vec3(1, -2, 0.5)) {
  const Quat r = g.rotation();
  std::vector<Vec3> p(n);
  for (auto& x : p)
    x = centre + r * Vec3(g.uniform(-offset, offset), g.uniform(-offset, offset), g.uniform(-2, 2));
  return p;
}

inline std::vector<Vec3> moved(const std::vector<Vec3>& p, const Quat& r, const Vec3& t) {
  std::vector<Vec3> out(p.size());
  for (size_t i = 0; i < p.size(); ++i) out[i] = r * p[i] + t;
  return out;
}

inline std::vector<double> random_masses(Gen& g, size_t n) {
  std::vector<double> m(n);
  for (auto& x : m) x = g.uniform(0.5, 2.0);
  return m;
}

}  // namespace phaco::shape_match::test
