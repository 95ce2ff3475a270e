#include "procedures/incision/scripted_incision.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <numbers>
#include <stdexcept>
#include <string>

#include "procedures/incision/surface_cutter.hpp"

namespace phaco::corneal_incision {
namespace {

void require_positive(double v, const char* field) {
  if (!std::isfinite(v) || !(v > 0.0))
    throw std::invalid_argument(std::string("scripted incision: ") + field +
                                " must be a finite positive number (mm)");
}

// The shoulders have passed the sphere: both ends lie on the blade's sides (full width).
bool full_width(const incision::BladeSection& s) {
  return s.touches && s.left_edge == incision::OutlineEdge::LeftSide &&
         s.right_edge == incision::OutlineEdge::RightSide;
}

}  // namespace

IncisionResult run_scripted_incision(cut::CutMesh& m, const incision::CorneaSpheres& spheres,
                                     const IncisionScript& script,
                                     const cut::CutSettings& settings) {
  incision::check_spheres(spheres);
  require_positive(script.step_mm, "step_mm");
  require_positive(script.measure_sample_mm, "measure_sample_mm");
  if (!std::isfinite(script.finish_min_angle_deg) ||
      (script.finish_min_angle_deg != 0.0 && !(script.finish_min_angle_deg >= 1.0)))
    throw std::invalid_argument(
        "scripted incision: finish_min_angle_deg must be 0 (no finishing) or >= 1 (the invariants' "
        "minimum angle, degrees)");
  if (!std::isfinite(script.max_advance_mm) || script.max_advance_mm < 0.0)
    throw std::invalid_argument(
        "scripted incision: max_advance_mm must be finite and >= 0 (0: the blade length)");
  incision::KeratomeBlade blade =
      incision::incision_start_blade(spheres.anterior_centre_z, spheres.anterior_radius_mm,
                                     spheres.limbus_radius_mm, script.approach, script.shape);
  const incision::BladeFrame frame = incision::blade_frame(blade);
  const Vec3 start = frame.tip;
  const double max_advance =
      script.max_advance_mm > 0.0 ? script.max_advance_mm : script.shape.length_mm;

  IncisionResult out;
  out.triangles_before = m.triangles.slots.live_count();
  out.particles_before = m.particles.slots.live_count();

  incision::WoundTracker tracker;
  SurfaceCutter outer, inner;
  cut::EditLog log;
  double total_ms = 0.0, cutting_ms = 0.0;
  const auto steps = static_cast<uint32_t>(std::floor(max_advance / script.step_mm + 1e-9));
  uint32_t last = 0;
  for (uint32_t k = 0; k <= steps; ++k) {
    last = k;
    blade.tip = start + (k * script.step_mm) * frame.d;
    const auto t0 = std::chrono::steady_clock::now();
    const incision::WoundFrame now = incision::update_wound(tracker, blade, spheres);
    bool made = cut_surface(m, outer, now.outer, settings, log, out.segments);
    made = cut_surface(m, inner, now.inner, settings, log, out.segments) || made;
    const double ms =
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    log.clear();
    total_ms += ms;
    out.frame_ms_max = std::max(out.frame_ms_max, ms);
    ++out.frames;
    if (made) ++out.cutting_frames, cutting_ms += ms;
    if (full_width(now.outer) && full_width(now.inner)) {
      out.passed = true;
      break;
    }
  }
  out.advance_mm = last * script.step_mm;
  if (script.finish_min_angle_deg > 0.0) {
    const auto t0 = std::chrono::steady_clock::now();
    out.finished =
        finish_surface(m, outer, settings, script.finish_min_angle_deg, log, out.segments);
    out.finished =
        finish_surface(m, inner, settings, script.finish_min_angle_deg, log, out.segments) ||
        out.finished;
    log.clear();
    out.finish_ms =
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  }
  out.frame_ms_mean = out.frames ? total_ms / out.frames : 0.0;
  out.cutting_frame_ms_mean = out.cutting_frames ? cutting_ms / out.cutting_frames : 0.0;

  // The tool leaves the mesh: remember the crack tips, end every path, withdraw the blade.
  const uint32_t outer_tips[2] = {live_tip(m, outer.side[0].path), live_tip(m, outer.side[1].path)};
  const uint32_t inner_tips[2] = {live_tip(m, inner.side[0].path), live_tip(m, inner.side[1].path)};
  for (SurfaceCutter* s : {&outer, &inner}) {
    for (SidePath& p : s->side) cut::end_cut(p.path);
  }
  out.outer_max_snap_mm = std::max(outer.side[0].path.max_snap_mm, outer.side[1].path.max_snap_mm);
  out.inner_max_snap_mm = std::max(inner.side[0].path.max_snap_mm, inner.side[1].path.max_snap_mm);
  for (uint32_t k = last; k-- > 0;) {
    blade.tip = start + (k * script.step_mm) * frame.d;
    incision::update_wound(tracker, blade, spheres);
  }
  out.wound = tracker.wound;
  out.port = tracker.port;
  out.triangles_after = m.triangles.slots.live_count();
  out.particles_after = m.particles.slots.live_count();

  out.outer = measure_surface_cut(m, spheres, Surface::Anterior, outer_tips[0], outer_tips[1],
                                  tool_polyline(outer), script.measure_sample_mm);
  out.inner = measure_surface_cut(m, spheres, Surface::Posterior, inner_tips[0], inner_tips[1],
                                  tool_polyline(inner), script.measure_sample_mm);
  if (out.outer.exists) {
    const Vec3& c = out.outer.middle;
    out.mesh_clock_hour = incision::clock_hour_of(c);
    out.mesh_limbus_distance_mm = spheres.limbus_radius_mm - std::hypot(c.x(), c.y());
  }
  if (out.outer.exists && out.inner.exists) {
    const Vec3 d = out.inner.middle - out.outer.middle;
    out.mesh_tunnel_length_mm = d.norm();
    if (out.mesh_tunnel_length_mm > 0.0)
      out.mesh_entry_angle_deg =
          std::asin(std::clamp(-d.z() / out.mesh_tunnel_length_mm, -1.0, 1.0)) * 180.0 /
          std::numbers::pi;
  }
  return out;
}

}  // namespace phaco::corneal_incision
