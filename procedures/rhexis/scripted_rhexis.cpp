#include "procedures/rhexis/scripted_rhexis.hpp"

#include <chrono>
#include <cmath>
#include <stdexcept>

namespace phaco::rhexis {
namespace {

constexpr double kPi = 3.14159265358979323846;

double polar_angle(const Vec3& p) {
  return std::atan2(p.y(), p.x());
}

}  // namespace

Vec3 surface_below(const cut::CutMesh& m, double x, double y, uint32_t& hint,
                   const cut::SnapSettings& snap) {
  // The capsule is a height field over the iris plane: the highest triangle over (x, y) holds the
  // point. A scan (scripting only, outside any timed step); off the mesh, the nearest point.
  const Triangles& tr = m.triangles;
  double best_z = -1e300;
  for (uint32_t t = 0; t < tr.slots.size(); ++t) {
    if (!tr.slots.alive(t)) continue;
    const Vec3 a = cut::particle_position(m.particles, tr.a[t]),
               b = cut::particle_position(m.particles, tr.b[t]),
               c = cut::particle_position(m.particles, tr.c[t]);
    const double det = (b.x() - a.x()) * (c.y() - a.y()) - (c.x() - a.x()) * (b.y() - a.y());
    if (std::abs(det) < 1e-300) continue;
    const double u = ((x - a.x()) * (c.y() - a.y()) - (c.x() - a.x()) * (y - a.y())) / det;
    const double v = ((b.x() - a.x()) * (y - a.y()) - (x - a.x()) * (b.y() - a.y())) / det;
    if (u < -1e-12 || v < -1e-12 || u + v > 1.0 + 1e-12) continue;
    const double z = a.z() + u * (b.z() - a.z()) + v * (c.z() - a.z());
    if (z > best_z) best_z = z, hint = t;
  }
  if (best_z > -1e300) return Vec3(x, y, best_z);
  const cut::CutPoint c = cut::locate_cut_point(m.particles, m.triangles, m.topology.adjacency,
                                                hint, Vec3(x, y, 10.0), snap);
  hint = c.triangle;
  return c.position;
}

RhexisResult run_scripted_rhexis(cut::CutMesh& m, const RhexisScript& s,
                                 const tear::TearSettings& tear, const cut::CutSettings& cut) {
  if (!(s.radius_mm > 0) || !(s.pull_mn > 0) || !(s.cystotome_sample_mm > 0) ||
      !(s.regrasp_every_deg > 0))
    throw std::invalid_argument(
        "scripted rhexis: radius_mm, pull_mn, cystotome_sample_mm and regrasp_every_deg must be > "
        "0");
  RhexisResult out;
  cut::CutPath path;
  cut::EditLog log;
  uint32_t hint = 0;

  // Cystotome: puncture at the centre, radial cut, then a bend onto the circle (the flap).
  const double r_bend = 0.8 * s.radius_mm, bend = s.flap_start_deg * kPi / 180.0;
  for (double r = 0.0; r < r_bend; r += s.cystotome_sample_mm)
    cut::cut_towards(m, path, surface_below(m, r, 0.0, hint, cut.snap), cut, log);
  const int bend_samples =
      std::max(4, static_cast<int>(std::ceil(1.6 * s.radius_mm * bend / s.cystotome_sample_mm)));
  for (int k = 0; k <= bend_samples; ++k) {
    const double f = static_cast<double>(k) / bend_samples;
    const double r = r_bend + (s.radius_mm - r_bend) * std::sin(0.5 * kPi * f), th = bend * f;
    cut::cut_towards(m, path, surface_below(m, r * std::cos(th), r * std::sin(th), hint, cut.snap),
                     cut, log);
  }
  if (path.tip == kInvalidIndex) return out;
  const Vec3 flap = cut::particle_position(m.particles, path.tip);
  out.flap_radius_mm = std::hypot(flap.x(), flap.y());

  // Tear, pulling the flap.
  tear::TearState state;
  double since_regrasp = 0.0, last_angle = polar_angle(flap), total_us = 0.0;
  for (uint32_t step = 0; step < s.max_tear_steps && !state.complete; ++step) {
    const Vec3 tip = cut::particle_position(m.particles, path.tip);
    const double th = polar_angle(tip), r = std::hypot(tip.x(), tip.y());
    Vec3 aim;
    const Vec3 radial(std::cos(th), std::sin(th), 0.0), tangent(-std::sin(th), std::cos(th), 0.0);
    if (s.pull == RhexisScript::Pull::Circular) {
      // Tangential, steered back onto the circle in proportion to the radial error.
      aim = tip + tangent + s.steer_per_mm * (s.radius_mm - r) * radial;
    } else {
      const double out_angle = s.outward_angle_deg * kPi / 180.0;
      aim = tip + std::cos(out_angle) * tangent + std::sin(out_angle) * radial;
    }
    const Vec3 force = s.pull_mn * (aim - tip).normalized();
    const auto t0 = std::chrono::steady_clock::now();
    tear::tear_step(m, path, state, force, tear, cut, log);
    const double us =
        std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - t0).count();
    total_us += us;
    out.tear_step_us_max = std::max(out.tear_step_us_max, us);
    ++out.tear_steps;
    // Regrasps: every regrasp_every_deg of tear progress round the axis.
    double d = polar_angle(cut::particle_position(m.particles, path.tip)) - last_angle;
    if (d > kPi) d -= 2 * kPi;
    if (d < -kPi) d += 2 * kPi;
    last_angle += d;
    since_regrasp += std::abs(d) * 180.0 / kPi;
    if (since_regrasp >= s.regrasp_every_deg) since_regrasp -= s.regrasp_every_deg, ++out.regrasps;
    if (r > s.radius_mm + 3.0) break;  // far out in the periphery: the drill is lost
  }
  out.tear_complete = state.complete;
  out.tear_advances = static_cast<uint32_t>(state.advances);
  out.runout_warnings = state.count(tear::TearEvent::RunoutWarning);
  out.radial_tearouts = state.count(tear::TearEvent::RadialTearout);
  out.max_radius_mm = state.max_radius_mm;
  for (const auto& e : state.events) {
    if (e.kind == tear::TearEvent::RunoutWarning && out.first_warning_radius_mm < 0)
      out.first_warning_radius_mm = e.radius_mm;
    if (e.kind == tear::TearEvent::RadialTearout && out.tearout_radius_mm < 0)
      out.tearout_radius_mm = e.radius_mm;
  }
  out.tear_step_us_mean = out.tear_steps ? total_us / out.tear_steps : 0.0;
  out.opening = measure_opening(m);
  return out;
}

}  // namespace phaco::rhexis
