#include "procedures/scene/track_pivot.hpp"

#include <algorithm>

#include "engine/core/error.hpp"
#include "procedures/scene/port_pivot.hpp"
#include "procedures/scene/scene.hpp"
#include "procedures/scene/tool_ports.hpp"

namespace phaco {

namespace {

// The port's frame: its axis, its width direction and their cross product, as columns.
Eigen::Matrix3d frame(const EyePort& p) {
  Eigen::Matrix3d m;
  const Vec3 w = (p.width_dir - p.width_dir.dot(p.axis) * p.axis).normalized();
  m.col(0) = p.axis.normalized();
  m.col(1) = w;
  m.col(2) = m.col(0).cross(w);
  return m;
}

}  // namespace

std::array<std::optional<TrackPivot>, 2> track_pivots(const Scene& scene) {
  std::array<std::optional<TrackPivot>, 2> out;
  if (!scene.carried.main_port || ports_mode(scene) != "measure") return out;
  const Guidance& g = scene.drill.guidance;
  if (!g.incision_site || !g.side_port) return out;  // no default port the track was made for
  const HandTrack* right = scene.scenario.find_hand(Hand::Right);
  if (!right || right->tool == ToolKind::Keratome) return out;
  TrackPivot p;
  try {
    p.from =
        default_ports(scene.params, g.incision_site->clock_hour, g.side_port->clock_hour).front();
  } catch (const InputError& e) {
    throw InputError(scene.scenario.source + ": eye: " + e.what());
  }
  p.to = *scene.carried.main_port;
  p.tool = right->tool;
  out[static_cast<size_t>(Hand::Right) & 1u] = p;
  return out;
}

ToolState pivot_track(const ToolState& pose, const TrackPivot& p) {
  ToolState out = pose;
  const Quat q = pose.quat.normalized();
  // 1 until carried_mm past the default port's centre, 0 from blend_mm further in.
  const double depth = (pose.pos - p.from.centre_mm).dot(p.from.axis) - p.carried_mm;
  const double w =
      p.blend_mm > 0 ? std::clamp(1.0 - depth / p.blend_mm, 0.0, 1.0) : (depth <= 0 ? 1.0 : 0.0);
  if (w > 0) {
    const Eigen::Matrix3d r = frame(p.to) * frame(p.from).transpose();  // default port → cut port
    const Vec3 moved = p.to.centre_mm + r * (pose.pos - p.from.centre_mm);
    out.pos = pose.pos + w * (moved - pose.pos);
    out.quat = q.slerp(w, (Quat(r) * q).normalized()).normalized();
  }
  return pivot_in_port(out, p.to, p.tool, p.aim_mm);
}

void pivot_track_pose(ToolState& pose, const std::optional<TrackPivot>& pivot) {
  if (pivot) pose = pivot_track(pose, *pivot);
}

}  // namespace phaco
