#include "systems/incision/keratome.hpp"

#include <cmath>
#include <numbers>
#include <stdexcept>
#include <string>

namespace phaco::incision {
namespace {

[[noreturn]] void fail(const std::string& field, const std::string& what) {
  throw std::invalid_argument("keratome blade: " + field + " " + what);
}

void require_finite(const Vec3& v, const char* field) {
  if (!v.allFinite()) fail(field, "is not finite");
}

void require_positive(double v, const char* field) {
  if (!std::isfinite(v) || v <= 0.0) fail(field, "must be a finite positive number (mm)");
}

// Lateral nearly parallel to the axis: its part across the axis below this fraction of its length.
constexpr double kMinLateralSine = 1e-6;

struct Frame2 {
  Vec3 d, l;
};

Frame2 orthonormal(const Vec3& axis, const Vec3& lateral) {
  require_finite(axis, "axis");
  require_finite(lateral, "lateral");
  const double na = axis.norm();
  if (!(na > 0.0)) fail("axis", "is zero (no direction of advance)");
  const Vec3 d = axis / na;
  const double nl = lateral.norm();
  if (!(nl > 0.0)) fail("lateral", "is zero");
  const Vec3 across = lateral - lateral.dot(d) * d;
  const double nc = across.norm();
  if (nc < kMinLateralSine * nl) fail("lateral", "is parallel to the axis");
  return {d, across / nc};
}

}  // namespace

BladeFrame blade_frame(const KeratomeBlade& blade) {
  require_finite(blade.tip, "tip");
  const Frame2 f = orthonormal(blade.axis, blade.lateral);
  const KeratomeShape& s = blade.shape;
  require_positive(s.width_mm, "width_mm");
  require_positive(s.thickness_mm, "thickness_mm");
  require_positive(s.length_mm, "length_mm");
  if (!std::isfinite(s.shoulder_mm) || s.shoulder_mm < 0.0)
    fail("shoulder_mm", "must be a finite number >= 0 (mm)");
  if (s.length_mm <= s.shoulder_mm) fail("length_mm", "must exceed shoulder_mm");
  return {blade.tip, f.d, f.l, f.l.cross(f.d)};
}

BladeOutline blade_outline(const BladeFrame& f, const KeratomeShape& shape) {
  const Vec3 half = 0.5 * shape.width_mm * f.l;
  const Vec3 shoulder = f.tip - shape.shoulder_mm * f.d;
  const Vec3 heel = f.tip - shape.length_mm * f.d;
  return {{f.tip, shoulder + half, heel + half, heel - half, shoulder - half}};
}

KeratomeBlade incision_start_blade(double anterior_centre_z, double anterior_radius_mm,
                                   double limbus_radius_mm, const IncisionApproach& a,
                                   const KeratomeShape& shape) {
  if (!std::isfinite(anterior_centre_z)) fail("anterior_centre_z", "is not finite");
  require_positive(anterior_radius_mm, "anterior_radius_mm");
  require_positive(limbus_radius_mm, "limbus_radius_mm");
  if (!std::isfinite(a.clock_hour)) fail("approach.clock_hour", "is not finite");
  if (!std::isfinite(a.limbus_distance_mm)) fail("approach.limbus_distance_mm", "is not finite");
  if (!std::isfinite(a.entry_angle_deg) || a.entry_angle_deg <= 0.0 || a.entry_angle_deg >= 90.0)
    fail("approach.entry_angle_deg", "must be in (0, 90) degrees");
  const double r = limbus_radius_mm - a.limbus_distance_mm;
  if (!(r > 0.0) || !(r < anterior_radius_mm))
    fail("approach.limbus_distance_mm",
         "puts the tip at radius " + std::to_string(r) + " mm, outside (0, anterior radius)");

  // Clock hour h: angle from +y toward +x of h·30°, so the radial unit is (sin θ, cos θ).
  const double theta = a.clock_hour / 12.0 * 2.0 * std::numbers::pi;
  const Vec3 radial(std::sin(theta), std::cos(theta), 0.0);
  const double alpha = a.entry_angle_deg * std::numbers::pi / 180.0;

  KeratomeBlade b;
  b.shape = shape;
  b.tip = r * radial;
  b.tip.z() = anterior_centre_z + std::sqrt(anterior_radius_mm * anterior_radius_mm - r * r);
  const Vec3 inward = -radial;
  b.axis = std::cos(alpha) * inward - std::sin(alpha) * Vec3::UnitZ();
  b.lateral = inward.cross(Vec3::UnitZ());
  blade_frame(b);  // checks the shape
  return b;
}

double clock_hour_of(const Vec3& p) {
  if (p.x() == 0.0 && p.y() == 0.0) return 12.0;
  double h = std::atan2(p.x(), p.y()) / (2.0 * std::numbers::pi) * 12.0;  // (-6, 6]
  if (h <= 0.0) h += 12.0;
  return h;
}

KeratomeBlade blade_from_tool_pose(const ToolPose& pose, const KeratomeShape& shape) {
  require_finite(pose.pos, "tool pose pos");
  if (!pose.quat.coeffs().allFinite() || !(pose.quat.norm() > 0.0))
    fail("tool pose quat", "is not a finite non-zero quaternion");
  const Quat q = pose.quat.normalized();
  KeratomeBlade b;
  b.tip = pose.pos;
  b.axis = -(q * Vec3::UnitZ());
  b.lateral = q * Vec3::UnitY();
  b.shape = shape;
  return b;
}

Quat tool_quat_for_blade(const Vec3& axis, const Vec3& lateral) {
  const Frame2 f = orthonormal(axis, lateral);
  Eigen::Matrix3d m;
  m.col(0) = f.d.cross(f.l);
  m.col(1) = f.l;
  m.col(2) = -f.d;
  Quat q(m);
  q.normalize();
  return q;
}

}  // namespace phaco::incision
