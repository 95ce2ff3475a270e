#include "engine/haptics/sample_bounds.hpp"

#include <algorithm>
#include <cmath>

namespace phaco {

SampleCheck bound_sample(DeviceSample& s) noexcept {
  if (!s.pos_mm.allFinite() || !s.quat.coeffs().allFinite() || !std::isfinite(s.grip) ||
      !std::isfinite(s.pedal)) {
    return SampleCheck::NonFinite;
  }
  const double norm = s.quat.norm();  // finite coefficients can still overflow the norm (1e200)
  if (!std::isfinite(norm) || !(norm > 1e-6)) return SampleCheck::NonFinite;
  // Not `!(|p| <= half)`: every coordinate is finite here, so the plain comparison is exact.
  if (s.pos_mm.cwiseAbs().maxCoeff() > kWorkspaceHalfMm) return SampleCheck::OutsideWorkspace;
  // A unit quaternion passes bit for bit (a replay must give back exactly what was recorded).
  if (std::abs(norm - 1.0) > 1e-9) s.quat.coeffs() /= norm;
  const double grip = std::clamp(s.grip, 0.0, kMaxGrip);
  const double pedal = std::clamp(s.pedal, 0.0, kMaxPedal);
  const bool clamped = grip != s.grip || pedal != s.pedal;
  s.grip = grip;
  s.pedal = pedal;
  return clamped ? SampleCheck::Clamped : SampleCheck::Ok;
}

}  // namespace phaco
