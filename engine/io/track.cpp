#include "engine/io/track.hpp"

#include <algorithm>
#include <cmath>

namespace phaco {

namespace {

ToolPose pose_of(const TrackSample& s) {
  return ToolPose{s.pos, s.quat, s.grip, s.pedal};
}

// Above this |cos| the arc is so short that sin(theta) loses precision; normalised linear
// interpolation is then accurate to well below 1e-12 rad.
constexpr double kNlerpCos = 0.9995;

}  // namespace

Quat slerp_shortest(const Quat& a, const Quat& b, double u) {
  double cos_theta = a.coeffs().dot(b.coeffs());
  // q and -q are the same rotation; flipping b keeps the path on the shorter arc.
  const Eigen::Vector4d bc =
      cos_theta < 0 ? Eigen::Vector4d(-b.coeffs()) : Eigen::Vector4d(b.coeffs());
  cos_theta = std::abs(cos_theta);
  Eigen::Vector4d c;
  if (cos_theta > kNlerpCos) {
    c = (1.0 - u) * a.coeffs() + u * bc;
  } else {
    const double theta = std::acos(std::min(cos_theta, 1.0));
    const double inv_sin = 1.0 / std::sin(theta);
    c = std::sin((1.0 - u) * theta) * inv_sin * a.coeffs() + std::sin(u * theta) * inv_sin * bc;
  }
  Quat q;
  q.coeffs() = c.normalized();
  return q;
}

ToolPose sample_track(std::span<const TrackSample> track, double t) {
  if (track.empty()) return ToolPose{};
  // Written as !(t > first) so that a NaN time holds the first sample instead of reading garbage.
  if (!(t > track.front().t)) return pose_of(track.front());
  if (t >= track.back().t) return pose_of(track.back());
  // First sample with time > t; it exists and is not the first, by the two checks above.
  const auto next = std::upper_bound(track.begin(), track.end(), t,
                                     [](double time, const TrackSample& s) { return time < s.t; });
  const TrackSample& a = *(next - 1);
  const TrackSample& b = *next;
  if (t == a.t) return pose_of(a);
  const double u = (t - a.t) / (b.t - a.t);
  ToolPose p;
  p.pos = a.pos + u * (b.pos - a.pos);
  p.quat = slerp_shortest(a.quat, b.quat, u);
  p.grip = a.grip + u * (b.grip - a.grip);
  p.pedal = a.pedal + u * (b.pedal - a.pedal);
  return p;
}

}  // namespace phaco
