#include "systems/lens_tools/crack.hpp"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <limits>
#include <memory>
#include <vector>

#include "engine/core/invariants.hpp"
#include "engine/schedule/parallel.hpp"

namespace phaco::lens_tools {

namespace {

constexpr uint32_t kNone = 0xffffffffu;
constexpr uint32_t kCrackGrain = 8192;      // cells per chunk of the scan near the tips
constexpr float kCrackBoxMarginMm = 1e-3f;  // the box around the tips' balls, widened

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
  const float contact2 = static_cast<float>(s.contact_radius_mm * s.contact_radius_mm);
  const float gap_r2 = static_cast<float>(s.gap_radius_mm * s.gap_radius_mm);
  // Every test below compares a distance with the contact radius (a tip touching a cell) or the
  // gap radius (a cell at the midpoint), so only the alive cells within those balls decide it: a
  // tip with no cell within the contact radius touches nothing, and then neither candidate
  // fragment engages. One scan lists those cells (a few dozen), in id order over fixed chunks
  // merged in id order; the nearest cells found on that list in id order (the lowest id among
  // equals) are the nearest over all cells, for any thread count. (It was two scans over every
  // cell: the nearest cell to each tip, then each candidate fragment's cells.)
  // The three balls lie in one box, widened by kCrackBoxMarginMm (≫ float rounding of the
  // distances): a cell outside the box is outside every ball, so one or two comparisons reject
  // most cells before the distances are computed (the list is the same).
  const float reach =
      static_cast<float>(std::max(s.contact_radius_mm, s.gap_radius_mm)) + kCrackBoxMarginMm;
  const Vec3f lo = p.cwiseMin(q).cwiseMin(m) - Vec3f::Constant(reach);
  const Vec3f hi = p.cwiseMax(q).cwiseMax(m) + Vec3f::Constant(reach);
  const uint32_t n = static_cast<uint32_t>(c.x.size());
  const std::vector<uint32_t> near = parallel_reduce_ordered(
      0u, n, kCrackGrain, std::vector<uint32_t>{},
      [&](uint32_t b, uint32_t e) {
        // The box test without branches (cells lie in no order along x, so a branch per cell
        // is mispredicted often): every index is written, the next write overwrites it unless
        // the cell is in the box. The buffer is not zeroed first (every entry read is written).
        const auto ids = std::make_unique_for_overwrite<uint32_t[]>(e - b + 1);
        uint32_t k = 0;
        for (uint32_t i = b; i < e; ++i) {
          const float x = c.x[i], y = c.y[i], z = c.z[i];
          ids[k] = i;
          k += (x >= lo.x()) & (x <= hi.x()) & (y >= lo.y()) & (y <= hi.y()) & (z >= lo.z()) &
               (z <= hi.z());
        }
        // The exact tests on the few in the box, in id order.
        uint32_t kept = 0;
        for (uint32_t j = 0; j < k; ++j) {
          const uint32_t i = ids[j];
          if (!c.alive[i]) continue;
          const Vec3f x(c.x[i], c.y[i], c.z[i]);
          if ((x - p).squaredNorm() <= contact2 || (x - q).squaredNorm() <= contact2 ||
              (x - m).squaredNorm() < gap_r2)
            ids[kept++] = i;
        }
        return std::vector<uint32_t>(ids.get(), ids.get() + kept);
      },
      [](std::vector<uint32_t> a, const std::vector<uint32_t>& b) {
        a.insert(a.end(), b.begin(), b.end());
        return a;
      });
  Nearest np_any, nq_any;  // nearest cell to each tip, if within the contact radius
  for (const uint32_t i : near) {
    const Vec3f x(c.x[i], c.y[i], c.z[i]);
    const float dp = (x - p).squaredNorm(), dq = (x - q).squaredNorm();
    if (dp <= contact2 && dp < np_any.d2) np_any = {i, dp};
    if (dq <= contact2 && dq < nq_any.d2) nq_any = {i, dq};
  }
  const double separation = (probe_tip - chopper_tip).norm();
  if (np_any.cell == kNone || nq_any.cell == kNone || separation <= 0) {
    state = CrackState{};
    return out;
  }
  // The fragment pushed is the probe's or the chopper's: per candidate, the other tip's nearest
  // cell of it and the nearest cell of it to the midpoint. Only its own cells bridge its trench: a
  // piece of another fragment lying in the trench (a quadrant that slid in after an earlier crack,
  // as the finer lenses' pieces do) holds nothing together.
  const uint32_t fp = c.label[np_any.cell], fq = c.label[nq_any.cell];
  Nearest q_on_fp, p_on_fq;
  float gap_fp = std::numeric_limits<float>::infinity(),
        gap_fq = std::numeric_limits<float>::infinity();
  for (const uint32_t i : near) {
    if (c.label[i] != fp && c.label[i] != fq) continue;
    const Vec3f x(c.x[i], c.y[i], c.z[i]);
    const float dm = (x - m).squaredNorm();
    if (c.label[i] == fp) {
      const float dq = (x - q).squaredNorm();
      if (dq < q_on_fp.d2) q_on_fp = {i, dq};
      gap_fp = std::min(gap_fp, dm);
    }
    if (c.label[i] == fq) {
      const float dp = (x - p).squaredNorm();
      if (dp < p_on_fq.d2) p_on_fq = {i, dp};
      gap_fq = std::min(gap_fq, dm);
    }
  }
  // Each tip touching the fragment, the trench (none of its cells) at their midpoint. A listed
  // cell's distance decides these as an unlisted one's would: beyond the radius either way.
  const bool on_fp = q_on_fp.d2 <= contact2 && gap_fp >= gap_r2;
  const bool on_fq = p_on_fq.d2 <= contact2 && gap_fq >= gap_r2;
  if (!on_fp && !on_fq) {
    state = CrackState{};
    return out;
  }
  const Nearest np = on_fp ? np_any : p_on_fq, nq = on_fp ? q_on_fp : nq_any;
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
