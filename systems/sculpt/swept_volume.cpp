#include "systems/sculpt/swept_volume.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <utility>
#include <vector>

namespace phaco::sculpt {

namespace {

struct Interval {
  double lo, hi;
};

// z-interval where the vertical line through (x, y) is within r of segment [a, b]; false if none.
bool line_capsule(double x, double y, const Vec3& a, const Vec3& b, double r, Interval& out) {
  double lo = 1e300, hi = -1e300;
  auto ball = [&](const Vec3& c) {
    const double q = (x - c.x()) * (x - c.x()) + (y - c.y()) * (y - c.y());
    if (q > r * r) return;
    const double h = std::sqrt(r * r - q);
    lo = std::min(lo, c.z() - h), hi = std::max(hi, c.z() + h);
  };
  ball(a);
  ball(b);
  const Vec3 d = b - a;
  const double dd = d.squaredNorm();
  if (dd > 1e-24) {
    // Points P(s) = (x, y, a.z + s): offset from the axis u + s·v, axial parameter t0 + s·dz/dd.
    const Vec3 w0(x - a.x(), y - a.y(), 0.0);
    const double t0 = w0.dot(d) / dd, dt = d.z() / dd;
    const Vec3 u = w0 - t0 * d;
    const Vec3 v = Vec3::UnitZ() - dt * d;
    double s_lo = -1e300, s_hi = 1e300;
    const double A = v.squaredNorm(), B = u.dot(v), C = u.squaredNorm() - r * r;
    bool ok = true;
    if (A > 1e-15) {
      const double disc = B * B - A * C;
      if (disc < 0)
        ok = false;
      else
        s_lo = (-B - std::sqrt(disc)) / A, s_hi = (-B + std::sqrt(disc)) / A;
    } else if (C > 0) {
      ok = false;
    }
    if (ok) {
      if (std::abs(dt) > 1e-300) {
        double s0 = -t0 / dt, s1 = (1.0 - t0) / dt;
        if (s0 > s1) std::swap(s0, s1);
        s_lo = std::max(s_lo, s0), s_hi = std::min(s_hi, s1);
      } else if (t0 < 0.0 || t0 > 1.0) {
        ok = false;
      }
      if (ok && s_lo <= s_hi) lo = std::min(lo, a.z() + s_lo), hi = std::max(hi, a.z() + s_hi);
    }
  }
  if (lo > hi) return false;
  out = {lo, hi};
  return true;
}

double integrate(std::span<const Vec3> path, double r, const LensShape& lens, double h,
                 uint64_t& columns) {
  Vec3 lo = path[0], hi = path[0];
  for (const Vec3& p : path) lo = lo.cwiseMin(p), hi = hi.cwiseMax(p);
  const double x0 = std::max(lo.x() - r, -lens.a), x1 = std::min(hi.x() + r, lens.a);
  const double y0 = std::max(lo.y() - r, -lens.a), y1 = std::min(hi.y() + r, lens.a);
  if (x0 >= x1 || y0 >= y1) return 0.0;
  // Columns on a grid anchored at the origin, so h and h/2 share their lines.
  const auto i0 = static_cast<int64_t>(std::floor(x0 / h)),
             i1 = static_cast<int64_t>(std::ceil(x1 / h));
  const auto j0 = static_cast<int64_t>(std::floor(y0 / h)),
             j1 = static_cast<int64_t>(std::ceil(y1 / h));
  std::vector<Interval> iv;
  double sum = 0.0;
  for (int64_t i = i0; i < i1; ++i) {
    const double x = (static_cast<double>(i) + 0.5) * h;
    for (int64_t j = j0; j < j1; ++j) {
      const double y = (static_cast<double>(j) + 0.5) * h;
      const double rho2 = (x * x + y * y) / (lens.a * lens.a);
      if (rho2 >= 1.0) continue;
      ++columns;
      const double k = std::sqrt(1.0 - rho2);
      const double z_top = lens.c_anterior * k, z_bottom = -lens.c_posterior * k;
      iv.clear();
      Interval one;
      if (path.size() == 1) {
        if (line_capsule(x, y, path[0], path[0], r, one)) iv.push_back(one);
      }
      for (size_t s = 0; s + 1 < path.size(); ++s)
        if (line_capsule(x, y, path[s], path[s + 1], r, one)) iv.push_back(one);
      if (iv.empty()) continue;
      std::sort(iv.begin(), iv.end(),
                [](const Interval& p, const Interval& q) { return p.lo < q.lo; });
      double len = 0.0, cur_lo = iv[0].lo, cur_hi = iv[0].hi;
      auto flush = [&] {
        const double l = std::max(cur_lo, z_bottom), u = std::min(cur_hi, z_top);
        if (u > l) len += u - l;
      };
      for (size_t m = 1; m < iv.size(); ++m) {
        if (iv[m].lo > cur_hi) {
          flush();
          cur_lo = iv[m].lo, cur_hi = iv[m].hi;
        } else {
          cur_hi = std::max(cur_hi, iv[m].hi);
        }
      }
      flush();
      sum += len;
    }
  }
  return sum * h * h;
}

}  // namespace

SweptVolume swept_volume_in_lens(std::span<const Vec3> path, double radius, const LensShape& lens,
                                 double column_mm) {
  if (path.empty()) throw std::invalid_argument("swept_volume_in_lens: empty path");
  if (!(radius >= 0.0)) throw std::invalid_argument("swept_volume_in_lens: negative radius");
  if (!(column_mm > 0.0))
    throw std::invalid_argument("swept_volume_in_lens: column size must be > 0");
  SweptVolume out;
  if (radius == 0.0) return out;
  uint64_t coarse_columns = 0;
  const double coarse = integrate(path, radius, lens, column_mm, coarse_columns);
  out.volume_mm3 = integrate(path, radius, lens, 0.5 * column_mm, out.columns);
  out.error_mm3 = std::abs(coarse - out.volume_mm3);
  return out;
}

}  // namespace phaco::sculpt
