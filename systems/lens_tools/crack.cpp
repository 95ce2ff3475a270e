#include "systems/lens_tools/crack.hpp"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <limits>

#include "engine/core/invariants.hpp"
#include "engine/schedule/parallel.hpp"

namespace phaco::lens_tools {

namespace {

constexpr uint32_t kNone = 0xffffffffu;
constexpr uint32_t kCrackGrain = 8192;  // cells per chunk of the nearest-cell scan

struct Nearest {
  uint32_t cell = kNone;
  float d2 = std::numeric_limits<float>::infinity();
};

}  // namespace

CrackPush push_apart(const CrackCells& c, const Vec3& probe_tip, const Vec3& chopper_tip,
                     const CrackSettings& s, CrackState& state) {
  assert(same_size(c.x, c.y, c.z, c.alive, c.hardness, c.label));
  CrackPush out;
  const Vec3f p = probe_tip.cast<float>(), q = chopper_tip.cast<float>();
  const Vec3f m = 0.5f * (p + q);
  // Nearest cells to each tip (the lowest id among equals) and to the midpoint, over fixed chunks
  // merged in id order: the same cells as one walk in id order, for any thread count.
  struct Scan {
    Nearest np, nq;
    float gap2 = std::numeric_limits<float>::infinity();
  };
  const uint32_t n = static_cast<uint32_t>(c.x.size());
  const Scan scan = parallel_reduce_ordered(
      0u, n, kCrackGrain, Scan{},
      [&](uint32_t b, uint32_t e) {
        Scan s;
        for (uint32_t i = b; i < e; ++i) {
          if (!c.alive[i]) continue;
          const Vec3f x(c.x[i], c.y[i], c.z[i]);
          const float dp = (x - p).squaredNorm(), dq = (x - q).squaredNorm(),
                      dm = (x - m).squaredNorm();
          if (dp < s.np.d2) s.np = {i, dp};
          if (dq < s.nq.d2) s.nq = {i, dq};
          s.gap2 = std::min(s.gap2, dm);
        }
        return s;
      },
      [](Scan a, const Scan& b) {
        if (b.np.d2 < a.np.d2) a.np = b.np;
        if (b.nq.d2 < a.nq.d2) a.nq = b.nq;
        a.gap2 = std::min(a.gap2, b.gap2);
        return a;
      });
  const Nearest np = scan.np, nq = scan.nq;
  const float gap2 = scan.gap2;
  const float contact2 = static_cast<float>(s.contact_radius_mm * s.contact_radius_mm);
  const float gap_r2 = static_cast<float>(s.gap_radius_mm * s.gap_radius_mm);
  const bool touching = np.cell != kNone && nq.cell != kNone && np.d2 <= contact2 &&
                        nq.d2 <= contact2 && c.label[np.cell] == c.label[nq.cell];
  const double separation = (probe_tip - chopper_tip).norm();
  if (!touching || gap2 < gap_r2 || separation <= 0) {
    state = CrackState{};
    return out;
  }
  const uint32_t fragment = c.label[np.cell];
  if (!state.engaged || state.fragment != fragment) {
    state.engaged = true;
    state.fragment = fragment;
    state.rest_separation_mm = separation;
  }
  state.rest_separation_mm = std::min(state.rest_separation_mm, separation);
  out.engaged = true;
  out.fragment = fragment;
  out.force_mn = s.stiffness_mn_mm * (separation - state.rest_separation_mm);
  const double hardness = 0.5 * (double(c.hardness[np.cell]) + double(c.hardness[nq.cell]));
  out.crack_force_mn = s.strength_mn * hardness;
  out.crack = out.force_mn >= out.crack_force_mn;
  out.mid = m.cast<double>();
  out.normal = (probe_tip - chopper_tip) / separation;
  if (out.crack) state = CrackState{};  // the fragment is gone: engage afresh on a piece
  return out;
}

void links_across(const CrackCells& c, std::span<const std::array<uint32_t, 4>> neighbour,
                  uint32_t fragment, const Vec3& mid, const Vec3& normal,
                  std::vector<std::pair<uint32_t, uint32_t>>& out) {
  // One neighbour row per cell (kNone or a cell).
  assert(same_size(c.x, c.y, c.z, c.alive, c.hardness, c.label, neighbour));
  out.clear();
  const Vec3f m = mid.cast<float>(), nn = normal.cast<float>();
  auto side = [&](uint32_t i) { return (Vec3f(c.x[i], c.y[i], c.z[i]) - m).dot(nn); };
  const uint32_t n = static_cast<uint32_t>(c.x.size());
  for (uint32_t i = 0; i < n; ++i) {
    if (!c.alive[i] || c.label[i] != fragment || side(i) >= 0.0f) continue;
    for (uint32_t k = 0; k < 4; ++k) {
      const uint32_t j = neighbour[i][k];
      if (j != kNone && c.alive[j] && side(j) >= 0.0f) out.push_back({i, k});
    }
  }
}

}  // namespace phaco::lens_tools
