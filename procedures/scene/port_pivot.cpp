#include "procedures/scene/port_pivot.hpp"

#include <algorithm>
#include <cmath>

#include "engine/io/tool_shape.hpp"

namespace phaco {

ToolPose pivot_in_port(const ToolPose& pose, const EyePort& port, ToolKind kind, double blend_mm) {
  ToolPose out = pose;
  const Quat q = pose.quat.normalized();
  const Vec3 bend = shaft_offset_local(kind);  // tip → shaft axis, ⟂ the shaft
  const Vec3 to_port = port.centre_mm - pose.pos;
  // How far the tip is past where the pivot begins, inward.
  const double past = -to_port.dot(port.axis) - bend.norm();
  const double w = blend_mm > 0 ? std::clamp(past / blend_mm, 0.0, 1.0) : (past > 0 ? 1.0 : 0.0);
  if (w <= 0 || to_port.norm() < 1e-9) {
    out.quat = q;
    return out;
  }
  // The axis passes the centre when tip → centre is bend + s·(+z) in the tool's frame, with
  // s = √(|to_port|² − |bend|²): turn that local vector onto to_port. A straight tool turns its +z
  // (the same arithmetic as before bent points were modelled: its poses are bit for bit).
  Vec3 from = q * Vec3::UnitZ();
  if (!bend.isZero()) {
    const double s = std::sqrt(std::max(0.0, to_port.squaredNorm() - bend.squaredNorm()));
    from = (q * (bend + s * Vec3::UnitZ())).normalized();
  }
  const Quat turn = Quat::FromTwoVectors(from, to_port.normalized());
  out.quat = q.slerp(w, (turn * q).normalized()).normalized();
  return out;
}

}  // namespace phaco
