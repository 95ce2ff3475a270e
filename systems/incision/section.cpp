#include "systems/incision/section.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>
#include <string>

namespace phaco::incision {
namespace {

// Relative tolerance on the quadratics' discriminants and on "on the sphere": a root this close to
// double counts as a tangent (one point), so a grazing blade gives one end, never NaN.
constexpr double kRelTol = 1e-12;
// Outline parameter slack: a crossing at a corner belongs to both edges that meet there.
constexpr double kEdgeSlack = 1e-12;

struct Crossings {
  int count = 0;
  double min_v = 0, max_v = 0;
  Vec3 min_p = Vec3::Zero(), max_p = Vec3::Zero();
  OutlineEdge min_edge = OutlineEdge::None, max_edge = OutlineEdge::None;

  void add(const Vec3& p, double v, OutlineEdge e) {
    if (count == 0 || v < min_v) min_v = v, min_p = p, min_edge = e;
    if (count == 0 || v > max_v) max_v = v, max_p = p, max_edge = e;
    ++count;
  }
};

// Roots of |A + t(B − A) − C|² = R² with t in [0, 1], added to `out`.
void cross_edge(const Vec3& a, const Vec3& b, const Vec3& c, double r2, const BladeFrame& f,
                OutlineEdge edge, Crossings& out) {
  const Vec3 e = b - a;
  const Vec3 w = a - c;
  const double qa = e.squaredNorm();
  const double qb = w.dot(e);
  const double qc = w.squaredNorm() - r2;
  double disc = qb * qb - qa * qc;
  const double tol = kRelTol * (qb * qb + std::abs(qa * qc));
  if (disc < -tol) return;
  disc = std::max(disc, 0.0);
  const double s = std::sqrt(disc);
  const double roots[2] = {(-qb - s) / qa, (-qb + s) / qa};
  const int n = s > 0.0 ? 2 : 1;
  for (int k = 0; k < n; ++k) {
    const double t = roots[k];
    if (t < -kEdgeSlack || t > 1.0 + kEdgeSlack) continue;
    const Vec3 p = a + std::clamp(t, 0.0, 1.0) * e;
    out.add(p, (p - f.tip).dot(f.l), edge);
  }
}

[[noreturn]] void fail_section(const std::string& field, const std::string& what) {
  throw std::invalid_argument("blade section: " + field + " " + what);
}

}  // namespace

double outline_signed_distance(const KeratomeShape& s, double u, double v) {
  const double half = 0.5 * s.width_mm;
  const double heel = u + s.length_mm;
  const double side = half - std::abs(v);
  // Bevel line through (0, 0) and (−s, ±W/2): inside where s·|v| + (W/2)·u <= 0.
  const double bevel = -(s.shoulder_mm * std::abs(v) + half * u) / std::hypot(s.shoulder_mm, half);
  return std::min({heel, side, bevel});
}

BladeSection blade_section(const KeratomeBlade& blade, double sphere_centre_z,
                           double sphere_radius_mm) {
  const BladeFrame f = blade_frame(blade);
  if (!std::isfinite(sphere_centre_z)) fail_section("sphere_centre_z", "is not finite");
  if (!std::isfinite(sphere_radius_mm) || sphere_radius_mm <= 0.0)
    fail_section("sphere_radius_mm", "must be a finite positive number (mm)");
  const KeratomeShape& shape = blade.shape;
  const Vec3 c(0.0, 0.0, sphere_centre_z);
  const double r2 = sphere_radius_mm * sphere_radius_mm;

  BladeSection out;

  // Puncture: P(t) = tip − t·d crosses the sphere at t = w·d + √((w·d)² − |w|² + R²), w = tip − C.
  const Vec3 w = f.tip - c;
  const double wc = w.squaredNorm() - r2;
  if (wc <= kRelTol * r2) {
    out.tip_inside = true;
    out.has_puncture = true;
    const double wd = w.dot(f.d);
    const double t = std::max(0.0, wd + std::sqrt(std::max(0.0, wd * wd - wc)));
    out.puncture = f.tip - t * f.d;
  }

  // The circle the blade plane cuts from the sphere.
  const double h = (c - f.tip).dot(f.n);
  const double rho2 = r2 - h * h;
  if (rho2 < -kRelTol * r2) return out;  // the plane misses the sphere
  const double rho = std::sqrt(std::max(0.0, rho2));
  const Vec3 cc = c - h * f.n;
  out.circle_radius_mm = rho;

  const BladeOutline o = blade_outline(f, shape);
  constexpr OutlineEdge kEdges[5] = {OutlineEdge::RightBevel, OutlineEdge::RightSide,
                                     OutlineEdge::Heel, OutlineEdge::LeftSide,
                                     OutlineEdge::LeftBevel};
  Crossings x;
  for (int k = 0; k < 5; ++k)
    cross_edge(o.corner[k], o.corner[(k + 1) % 5], c, r2, f, kEdges[k], x);

  const auto in_plane = [&](const Vec3& p) {
    return outline_signed_distance(shape, (p - f.tip).dot(f.d), (p - f.tip).dot(f.l));
  };

  if (x.count == 0) {
    // No boundary crossing: either no cut, or the whole circle lies inside the outline.
    if (in_plane(cc) < rho) return out;
    out.touches = true;
    out.closed = true;
    out.left = cc - rho * f.l;
    out.right = cc + rho * f.l;
    out.left_v = (out.left - f.tip).dot(f.l);
    out.right_v = (out.right - f.tip).dot(f.l);
    out.middle = cc + rho * f.d;
    out.width_mm = 2.0 * rho;
    out.arc_mm = 2.0 * std::numbers::pi * rho;
    return out;
  }

  out.touches = true;
  out.left = x.min_p;
  out.right = x.max_p;
  out.left_edge = x.min_edge;
  out.right_edge = x.max_edge;
  out.left_v = x.min_v;
  out.right_v = x.max_v;
  const double chord = (out.right - out.left).norm();
  out.width_mm = chord;
  if (chord <= kRelTol * sphere_radius_mm || rho <= 0.0) {
    out.middle = out.left;
    return out;
  }

  // Middle of the cut arc: the minor arc's middle if it lies on the blade, else the major arc's.
  const Vec3 mid = 0.5 * (out.left + out.right) - cc;
  Vec3 dir = mid;
  if (dir.norm() <= kRelTol * rho) dir = f.n.cross(out.right - out.left);  // a half circle
  dir.normalize();
  const double minor = 2.0 * rho * std::asin(std::min(1.0, 0.5 * chord / rho));
  const Vec3 m_minor = cc + rho * dir;
  const Vec3 m_major = cc - rho * dir;
  if (in_plane(m_minor) >= in_plane(m_major)) {
    out.middle = m_minor;
    out.arc_mm = minor;
  } else {
    out.middle = m_major;
    out.arc_mm = 2.0 * std::numbers::pi * rho - minor;
  }
  return out;
}

}  // namespace phaco::incision
