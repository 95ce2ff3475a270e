#include "procedures/scene/port_pivot.hpp"

#include <algorithm>

namespace phaco {

ToolPose pivot_in_port(const ToolPose& pose, const EyePort& port, double blend_mm) {
  ToolPose out = pose;
  const Quat q = pose.quat.normalized();
  const Vec3 to_port = port.centre_mm - pose.pos;
  const double past = -to_port.dot(port.axis);  // how far the tip is past the centre, inward
  const double w = blend_mm > 0 ? std::clamp(past / blend_mm, 0.0, 1.0) : (past > 0 ? 1.0 : 0.0);
  if (w <= 0 || to_port.norm() < 1e-9) {
    out.quat = q;
    return out;
  }
  const Quat turn = Quat::FromTwoVectors(q * Vec3::UnitZ(), to_port.normalized());
  out.quat = q.slerp(w, (turn * q).normalized()).normalized();
  return out;
}

}  // namespace phaco
