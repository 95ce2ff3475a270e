#include "systems/lens_tools/constraints.hpp"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <limits>

#include "engine/core/invariants.hpp"
#include "engine/schedule/parallel.hpp"

namespace phaco::lens_tools {

namespace {

constexpr uint32_t kConstraintGrain = 2048;
constexpr double kSkinMm = 1e-5;  // ≫ float rounding at eye scale (≈ 5e-7 mm), ≪ any cell size
constexpr double kFastMarginMm = 1e-4;  // float inside-test margin, ≫ its rounding error

bool present(const Ball& b) {
  return b.radius_mm > 0;
}

bool in_ball(const Vec3& p, const Ball& b, double tol) {
  return !present(b) || (p - b.centre).squaredNorm() <= (b.radius_mm + tol) * (b.radius_mm + tol);
}

Vec3 onto_ball(const Vec3& p, const Ball& b) {
  const Vec3 d = p - b.centre;
  const double len = d.norm();
  if (len <= b.radius_mm) return p;
  if (len == 0) return p;
  return b.centre + d * (b.radius_mm / len);
}

// Nearest point of the circle where the spheres of a and b meet; false when they do not meet.
bool onto_rim(const Vec3& p, const Ball& a, const Ball& b, Vec3& out) {
  const Vec3 ab = b.centre - a.centre;
  const double d = ab.norm();
  const double ra = a.radius_mm, rb = b.radius_mm;
  if (!(d > std::abs(ra - rb)) || !(d < ra + rb)) return false;
  const Vec3 n = ab / d;
  const double h = (d * d + ra * ra - rb * rb) / (2 * d);
  const Vec3 cc = a.centre + h * n;
  const double rc = std::sqrt(std::max(ra * ra - h * h, 0.0));
  Vec3 u = p - cc;
  u -= u.dot(n) * n;
  double len = u.norm();
  if (len < 1e-12) {  // on the rim's axis: every rim point is nearest; take one
    u = n.unitOrthogonal();
    len = 1;
  }
  out = cc + u * (rc / len);
  return true;
}

}  // namespace

Ball cap_sphere(double equator_radius_mm, double pole_z_mm, CapFit fit) {
  const double c = std::abs(pole_z_mm), a2 = equator_radius_mm * equator_radius_mm;
  const double through = (a2 + c * c) / (2 * c);
  const double r = fit == CapFit::ThroughEquator ? through : std::max(a2 / c, through);
  return {Vec3(0, 0, pole_z_mm - std::copysign(r, pole_z_mm)), r};
}

EyeBounds eye_bounds(double equator_radius_mm, double anterior_pole_z_mm,
                     double posterior_pole_z_mm, double cornea_posterior_apex_z_mm,
                     double cornea_posterior_radius_mm, double rhexis_radius_mm, CapFit fit) {
  EyeBounds b;
  b.cornea = {Vec3(0, 0, cornea_posterior_apex_z_mm - cornea_posterior_radius_mm),
              cornea_posterior_radius_mm};
  b.anterior_capsule = cap_sphere(equator_radius_mm, anterior_pole_z_mm, fit);
  b.posterior_capsule = cap_sphere(equator_radius_mm, posterior_pole_z_mm, fit);
  b.rhexis_radius_mm = rhexis_radius_mm;
  return b;
}

Vec3 project_into(const Vec3& p, const Ball& a, const Ball& b, double skin_mm) {
  if (in_ball(p, a, 0) && in_ball(p, b, 0)) return p;
  Ball as = a, bs = b;  // shrunk by the skin: the result lands strictly inside
  if (present(as)) as.radius_mm = std::max(a.radius_mm - skin_mm, 0.5 * a.radius_mm);
  if (present(bs)) bs.radius_mm = std::max(b.radius_mm - skin_mm, 0.5 * b.radius_mm);
  if (!present(bs)) return onto_ball(p, as);
  if (!present(as)) return onto_ball(p, bs);
  constexpr double kTol = 1e-12;
  const Vec3 qa = onto_ball(p, as);
  if (in_ball(qa, bs, kTol)) return qa;
  const Vec3 qb = onto_ball(p, bs);
  if (in_ball(qb, as, kTol)) return qb;
  Vec3 rim;
  if (onto_rim(p, as, bs, rim)) return rim;
  return qb;  // disjoint balls: no allowed point; the later ball wins
}

bool inside_bounds(const Vec3& p, const EyeBounds& bounds, double tolerance_mm) {
  const bool opening =
      bounds.rhexis_radius_mm > 0 &&
      p.x() * p.x() + p.y() * p.y() < bounds.rhexis_radius_mm * bounds.rhexis_radius_mm;
  return (opening || in_ball(p, bounds.anterior_capsule, tolerance_mm)) &&
         in_ball(p, bounds.posterior_capsule, tolerance_mm) &&
         in_ball(p, bounds.cornea, tolerance_mm);
}

SurelyInside::SurelyInside(const EyeBounds& bounds, double tolerance_mm) {
  auto ball = [&](const Ball& b) {
    FloatBall f;
    f.present = present(b);
    if (!f.present) return f;
    f.cx = static_cast<float>(b.centre.x()), f.cy = static_cast<float>(b.centre.y()),
    f.cz = static_cast<float>(b.centre.z());
    const float r = static_cast<float>(std::max(b.radius_mm + tolerance_mm - kFastMarginMm, 0.0));
    f.r2 = r * r;
    return f;
  };
  cornea = ball(bounds.cornea), anterior = ball(bounds.anterior_capsule),
  posterior = ball(bounds.posterior_capsule);
  const double open = bounds.rhexis_radius_mm - kFastMarginMm;
  if (bounds.rhexis_radius_mm > 0 && open > 0) open2 = static_cast<float>(open * open);
}

namespace {

// A float ball a little smaller than the real one (by kFastMarginMm): a cell inside it is surely
// inside the real ball, whatever float rounding did. Absent balls take every cell.
struct FastBall {
  float cx = 0, cy = 0, cz = 0, r2 = std::numeric_limits<float>::infinity();
  explicit FastBall(const Ball& b) {
    if (!present(b)) return;
    cx = static_cast<float>(b.centre.x()), cy = static_cast<float>(b.centre.y()),
    cz = static_cast<float>(b.centre.z());
    const float r = static_cast<float>(std::max(b.radius_mm - kFastMarginMm, 0.0));
    r2 = r * r;
  }
  bool surely_inside(float x, float y, float z) const {
    const float dx = x - cx, dy = y - cy, dz = z - cz;
    return dx * dx + dy * dy + dz * dz <= r2;
  }
};

}  // namespace

void constrain(const CellSpans& cells, const EyeBounds& bounds, std::span<uint8_t> contact) {
  // No flags, or one per cell (a short flag column would otherwise be ignored without a word).
  assert(cells.in_step() && (contact.empty() || contact.size() == cells.size()));
  const bool flags = contact.size() == cells.size();
  const FastBall cornea(bounds.cornea), anterior(bounds.anterior_capsule),
      posterior(bounds.posterior_capsule);
  const double rhexis = std::max(bounds.rhexis_radius_mm, 0.0);
  // Cells near the opening's edge take the exact (double) path, so the float test below never
  // decides which set a cell belongs to.
  const float rhexis_in2 = static_cast<float>(std::max(rhexis - kFastMarginMm, 0.0) *
                                              std::max(rhexis - kFastMarginMm, 0.0));
  const float rhexis_out2 = static_cast<float>((rhexis + kFastMarginMm) * (rhexis + kFastMarginMm));
  const bool has_rhexis = rhexis > 0;
  // One block of at most kConstraintGrain cells (what a parallel_for chunk is; the loop below
  // splits anyway).
  auto block = [&](uint32_t b, uint32_t e) {
    // Pass 1, branch-free: which cells might be outside (most are well inside every ball).
    uint8_t suspect[kConstraintGrain];
    const float* __restrict x = cells.x.data();
    const float* __restrict y = cells.y.data();
    const float* __restrict z = cells.z.data();
    const uint8_t* __restrict alive = cells.alive.data();
    for (uint32_t i = b; i < e; ++i) {
      const float fx = x[i], fy = y[i], fz = z[i];
      const float r2 = fx * fx + fy * fy;
      const bool surely_open = has_rhexis & (r2 < rhexis_in2);
      const bool surely_closed = !has_rhexis | (r2 > rhexis_out2);
      const bool safe = (surely_open | surely_closed) & posterior.surely_inside(fx, fy, fz) &
                        cornea.surely_inside(fx, fy, fz) &
                        (surely_open | anterior.surely_inside(fx, fy, fz));
      suspect[i - b] = (alive[i] != 0) & !safe;
    }
    if (flags) std::fill(contact.begin() + b, contact.begin() + e, uint8_t{0});
    // Pass 2: the exact projection, only for the suspects.
    for (uint32_t i = b; i < e; ++i) {
      if (!suspect[i - b]) continue;
      const float fx = cells.x[i], fy = cells.y[i], fz = cells.z[i];
      const Vec3 p(fx, fy, fz);
      const bool opening = rhexis > 0 && p.x() * p.x() + p.y() * p.y() < rhexis * rhexis;
      // Inside the opening the posterior cap and the cornea bound the cell; elsewhere the bag, and
      // the cornea after it (slack for a bag that lies below the cornea, as in every real eye).
      Vec3 q = opening
                   ? project_into(p, bounds.posterior_capsule, bounds.cornea, kSkinMm)
                   : project_into(p, bounds.anterior_capsule, bounds.posterior_capsule, kSkinMm);
      if (!opening) q = project_into(q, bounds.cornea, Ball{}, kSkinMm);
      if (q == p) continue;
      const Vec3 out = p - q;  // outward normal of the set at q (convex set)
      const double len = out.norm();
      if (len > 0) {
        const Vec3 n = out / len;
        const Vec3 v(cells.vx[i], cells.vy[i], cells.vz[i]);
        const double vn = v.dot(n);
        if (vn > 0) {
          const Vec3 w = v - vn * n;
          cells.vx[i] = static_cast<float>(w.x());
          cells.vy[i] = static_cast<float>(w.y());
          cells.vz[i] = static_cast<float>(w.z());
        }
      }
      cells.x[i] = static_cast<float>(q.x());
      cells.y[i] = static_cast<float>(q.y());
      cells.z[i] = static_cast<float>(q.z());
      if (flags) contact[i] = 1;
    }
  };
  parallel_for(0, cells.size(), kConstraintGrain, [&](uint32_t b, uint32_t e, int) {
    for (uint32_t s = b; s < e; s += kConstraintGrain) block(s, std::min(e, s + kConstraintGrain));
  });
}

}  // namespace phaco::lens_tools
