#include "systems/incision/port_arc.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>
#include <string>

namespace phaco::incision {
namespace {

constexpr double kTwoPi = 2.0 * std::numbers::pi;
// The largest sweep a pair of versors can stand for (start = end would read as an empty arc).
constexpr double kMaxSweep = kTwoPi - 1e-9;

[[noreturn]] void fail(const std::string& field, const std::string& what) {
  throw std::invalid_argument("port arc: " + field + " " + what);
}

double angle_of(const Eigen::Vector2d& v) {
  return std::atan2(v.y(), v.x());
}

// x wrapped into [0, 2π).
double wrap(double x) {
  x = std::fmod(x, kTwoPi);
  if (x < 0.0) x += kTwoPi;
  return x >= kTwoPi ? 0.0 : x;
}

Eigen::Vector2d versor(double angle) {
  return {std::cos(angle), std::sin(angle)};
}

Eigen::Vector2d radial_versor(const Vec3& p, const char* field) {
  if (!p.allFinite()) fail(field, "is not finite");
  const Eigen::Vector2d xy(p.x(), p.y());
  const double n = xy.norm();
  if (!(n > 0.0)) fail(field, "is on the optical axis (no radial direction)");
  return xy / n;
}

}  // namespace

double port_sweep_rad(const PortArc& port) {
  return wrap(angle_of(port.end) - angle_of(port.start));
}

PortSize port_size(const PortArc& port) {
  if (!port.open) return {};
  const double a = port_sweep_rad(port);
  return {a, 2.0 * port.radius_mm * std::sin(0.5 * a), port.radius_mm * a};
}

void widen_port(PortArc& port, const Vec3& a, const Vec3& b) {
  const Eigen::Vector2d va = radial_versor(a, "end a");
  const Eigen::Vector2d vb = radial_versor(b, "end b");

  // The cut's own arc: the shorter way from one end to the other.
  double new_start = angle_of(va);
  double new_sweep = wrap(angle_of(vb) - new_start);
  if (new_sweep > std::numbers::pi) {
    new_start = angle_of(vb);
    new_sweep = kTwoPi - new_sweep;
  }

  double start = new_start, sweep = new_sweep;
  if (port.open) {
    // Smallest arc holding both: it starts at one of the two starts; from a start σ it must reach
    // the far end of each arc counter-clockwise. The old start wins ties, so a port does not turn
    // when nothing new is cut.
    const double old_start = angle_of(port.start);
    const double old_sweep = port_sweep_rad(port);
    const auto need = [&](double sigma) {
      return std::max(wrap(old_start - sigma) + old_sweep, wrap(new_start - sigma) + new_sweep);
    };
    const double from_old = need(old_start), from_new = need(new_start);
    if (from_old <= from_new) {
      start = old_start;
      sweep = from_old;
    } else {
      start = new_start;
      sweep = from_new;
    }
  }
  sweep = std::min(sweep, kMaxSweep);
  port.open = true;
  port.start = versor(start);
  port.end = versor(start + sweep);
  port.radius_mm = 0.5 * (std::hypot(a.x(), a.y()) + std::hypot(b.x(), b.y()));
  port.z_mm = 0.5 * (a.z() + b.z());
}

bool port_passes(const PortArc& port, const Vec3& point, const PortTolerance& tol) {
  if (!point.allFinite()) fail("point", "is not finite");
  if (!(tol.radial_mm >= 0.0) || !(tol.z_mm >= 0.0) || !(tol.lateral_mm >= 0.0) ||
      !std::isfinite(tol.radial_mm + tol.z_mm + tol.lateral_mm))
    fail("tolerance", "values must be finite and >= 0 (mm)");
  if (!port.open) return false;
  const double rp = std::hypot(point.x(), point.y());
  if (std::abs(rp - port.radius_mm) > tol.radial_mm) return false;
  if (std::abs(point.z() - port.z_mm) > tol.z_mm) return false;
  if (!(rp > 0.0)) return false;
  const double slack = port.radius_mm > 0.0 ? tol.lateral_mm / port.radius_mm : 0.0;
  const double off = wrap(std::atan2(point.y(), point.x()) - angle_of(port.start));
  return off <= port_sweep_rad(port) + slack || off >= kTwoPi - slack;
}

Vec3 port_middle(const PortArc& port) {
  const Eigen::Vector2d v = versor(angle_of(port.start) + 0.5 * port_sweep_rad(port));
  return {port.radius_mm * v.x(), port.radius_mm * v.y(), port.z_mm};
}

Vec3 nearest_on_port(const PortArc& port, const Vec3& point) {
  if (!port.open) fail("port", "is not open");
  if (!point.allFinite()) fail("point", "is not finite");
  const double rp = std::hypot(point.x(), point.y());
  if (!(rp > 0.0)) return port_middle(port);
  const double start = angle_of(port.start);
  const double sweep = port_sweep_rad(port);
  const double off = wrap(std::atan2(point.y(), point.x()) - start);
  double at = off;
  if (off > sweep) at = (off - sweep) < (kTwoPi - off) ? sweep : 0.0;
  const Eigen::Vector2d v = versor(start + at);
  return {port.radius_mm * v.x(), port.radius_mm * v.y(), port.z_mm};
}

}  // namespace phaco::incision
