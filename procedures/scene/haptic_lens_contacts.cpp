#include "procedures/scene/haptic_lens_contacts.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>

#include "components/held_fragment.hpp"
#include "components/tets.hpp"
#include "components/tool.hpp"
#include "procedures/scene/lens_fragments.hpp"
#include "procedures/scene/lens_sculpting.hpp"
#include "procedures/scene/scene.hpp"

namespace phaco {
namespace {

// cell_spheres' float pre-test: cells per block, and its margin beyond the double test's reach.
constexpr uint32_t kHapticScanBlock = 64;
constexpr double kHapticScanMarginMm = 1e-3;

double equal_volume_radius(double volume_mm3) {
  return std::cbrt(3.0 * std::max(0.0, volume_mm3) / (4.0 * std::numbers::pi));
}

// The scratch's candidates, nearest first, into the tool's spheres (at most its capacity).
template <class Sphere>
void keep_nearest(HapticLensScratch& s, HapticTool& t, Sphere&& sphere) {
  const size_t keep = std::min<size_t>(s.near.size(), kHapticMaxSpheres);
  std::partial_sort(s.near.begin(), s.near.begin() + static_cast<std::ptrdiff_t>(keep),
                    s.near.end());
  t.sphere_count = static_cast<uint32_t>(keep);
  for (size_t k = 0; k < keep; ++k) sphere(s.near[k].second, static_cast<uint32_t>(k));
}

// Tets lens (seed 000 §5.3): surface tets near the tip, from the sculpting's broadphase in the
// lens's rest frame, turned by the nucleus angle. Only the kHapticMaxSpheres nearest are kept, so
// the search grows from a small radius until it holds that many (or reaches `reach`): its cost
// follows the tets in a ball holding that many surface tets, the same at every resolution, where a
// search of the whole reach costs the tets within 1 mm of the tip (about 100k at level 8, 9.7 ms
// per frame in the sweep).
void tet_spheres(const Scene& scene, const LensSculpting& ls, const Vec3& tip, double reach,
                 const HapticLensSettings& settings, HapticLensScratch& s, HapticTool& t) {
  const Tets* tets = scene.world.get<Tets>(*scene.body(BodyPart::Lens));
  const double angle = ls.rotation.angle_rad, c = std::cos(angle), sn = std::sin(angle);
  const Vec3 local(c * tip.x() + sn * tip.y(), -sn * tip.x() + c * tip.y(), tip.z());
  const TetTopology& topo = ls.topology;
  if (s.tets_of != topo.tet_count) {  // once per lens: removed tets keep their rest volume
    s.mean_radius_mm = 0.0;
    for (uint32_t e = 0; e < topo.tet_count; ++e)
      s.mean_radius_mm += equal_volume_radius(topo.volume[e]);
    s.mean_radius_mm /= std::max(1u, topo.tet_count);
    s.tets_of = topo.tet_count;
  }
  // A surface through the tip holds about (r / mean radius)² tets within r: start where that is
  // the count wanted, (256)^½ = 16 mean radii, a little short so that one step usually ends it.
  double radius = std::min(reach, 12.0 * s.mean_radius_mm);
  for (;;) {
    // A tet with gap ≤ radius has its centre within radius + its own radius of the tip: the
    // margin of two mean radii catches all but the rare large tet at the edge of the search.
    const sculpt::TipCapsule query{local, local, radius + 2.0 * s.mean_radius_mm};
    s.candidates.clear();
    sculpt::BroadphaseStats stats;
    if (ls.sculpt.options.broadphase == sculpt::Broadphase::Octree) {
      sculpt::octree_candidates(ls.sculpt.octree, topo, query, s.queue, s.candidates, stats);
    } else {
      ls.sculpt.dbvt.candidates(topo, query, s.candidates, stats);
    }
    // No sort of the candidates: keep_nearest orders by (gap, tet), whatever the broadphase's
    // order.
    s.near.clear();
    for (uint32_t e : s.candidates) {
      if (e >= topo.tet_count || !topo.alive[e] || topo.surface_slot[e] == kNoTet) continue;
      const Vec3 centre = sculpt::tet_centre(topo, e);
      const double gap = (centre - local).norm() - equal_volume_radius(topo.volume[e]);
      if (gap > radius) continue;
      s.near.emplace_back(static_cast<float>(gap), e);
    }
    if (s.near.size() >= kHapticMaxSpheres || radius >= reach) break;
    // Surface tets grow as the radius squared: aim at the count, at least ×1.25, at most ×2.
    const double aim =
        std::sqrt(double(kHapticMaxSpheres) / double(std::max<size_t>(s.near.size(), 1)));
    radius = std::min(reach, radius * std::clamp(1.1 * aim, 1.25, 2.0));
  }
  const double h = settings.nucleus_hardness;
  keep_nearest(s, t, [&](uint32_t e, uint32_t k) {
    const Vec3 r = sculpt::tet_centre(topo, e);
    t.sphere_x[k] = static_cast<float>(c * r.x() - sn * r.y());
    t.sphere_y[k] = static_cast<float>(sn * r.x() + c * r.y());
    t.sphere_z[k] = static_cast<float>(r.z());
    t.sphere_r[k] = static_cast<float>(equal_volume_radius(topo.volume[e]));
    const bool nucleus = !tets || e >= tets->region.size() || tets->region[e] != 0;
    t.sphere_k[k] =
        static_cast<float>(settings.stiffness_mn_mm * (nucleus ? h : 0.5 * h) / kStandardHardness);
  });
}

// Each cell's equal-volume radius and the largest, once per lens: a cell's volume never changes.
void size_cells(const SimplexCells& cells, HapticLensScratch& s) {
  if (s.cells_of == cells.size() && s.cell_radius_mm.size() == cells.size()) return;
  s.cell_radius_mm.resize(cells.size());
  s.max_cell_radius_mm = 0.0;
  for (uint32_t e = 0; e < cells.size(); ++e) {
    s.cell_radius_mm[e] = equal_volume_radius(cells.volume[e]);
    s.max_cell_radius_mm = std::max(s.max_cell_radius_mm, s.cell_radius_mm[e]);
  }
  s.cells_of = cells.size();
}

// A cell with its gap within the reach has its centre within reach + its radius: the largest
// radius bounds that, and the cube root is then taken once per lens, not per cell.
double cell_search_radius(double reach, const HapticLensScratch& s) {
  return reach + s.max_cell_radius_mm + 1e-6;
}

// Per tip, the cells whose centre a float test puts within `far` of it, ids ascending: blocks of
// the position columns, each block read once for every tip (the scan is bound by reading them),
// the test vectorised. It only drops cells beyond far + kHapticScanMarginMm, far more than float
// rounding at lens coordinates (~1e-6 mm), so the double test after it keeps the same cells.
// out[t] keeps its size (a cell each) from frame to frame; its first count[t] entries are the
// scan's.
void scan_cells(const SimplexCells& cells, std::span<const Vec3> tips, std::span<const double> far,
                std::span<std::vector<uint32_t>* const> out, std::span<uint32_t> count) {
  constexpr size_t kMaxTips = 8;
  const size_t k = std::min(tips.size(), kMaxTips);
  std::array<float, kMaxTips> tx{}, ty{}, tz{}, ff2{};
  for (size_t t = 0; t < k; ++t) {
    tx[t] = static_cast<float>(tips[t].x()), ty[t] = static_cast<float>(tips[t].y());
    tz[t] = static_cast<float>(tips[t].z());
    const auto ff = static_cast<float>(far[t] + kHapticScanMarginMm);
    ff2[t] = ff * ff;
    // Room for every cell, so the scan appends without a check per cell (grown once per lens).
    if (out[t]->size() < cells.size()) out[t]->resize(cells.size());
  }
  std::array<uint32_t, kMaxTips> found{};
  const float* X = cells.x.data();
  const float* Y = cells.y.data();
  const float* Z = cells.z.data();
  const auto n = static_cast<uint32_t>(cells.size());
  for (uint32_t b = 0; b < n; b += kHapticScanBlock) {
    const uint32_t m = std::min(kHapticScanBlock, n - b);
    for (size_t t = 0; t < k; ++t) {
      uint8_t hit[kHapticScanBlock];
      uint8_t any = 0;
      for (uint32_t i = 0; i < m; ++i) {
        const float dx = X[b + i] - tx[t], dy = Y[b + i] - ty[t], dz = Z[b + i] - tz[t];
        hit[i] = dx * dx + dy * dy + dz * dz <= ff2[t];
        any |= hit[i];
      }
      if (!any) continue;
      // Appended without a branch per cell: which of the 64 are near is not predictable.
      uint32_t* o = out[t]->data();
      uint32_t at = found[t];
      for (uint32_t i = 0; i < m; ++i) {
        o[at] = b + i;
        at += hit[i];
      }
      found[t] = at;
    }
  }
  for (size_t t = 0; t < k; ++t) count[t] = found[t];
}

// Fragment lens (seed 002 §4): alive cells with an external face, less the held fragment's, from
// the cells the scan found near the tip.
void cell_spheres(const LensFragments& lf, const Vec3& tip, double reach, uint32_t held_fragment,
                  std::span<const uint32_t> scanned, const HapticLensSettings& settings,
                  HapticLensScratch& s, HapticTool& t) {
  const SimplexCells& cells = lf.lens.cells;
  const std::vector<uint32_t>& label = lf.lens.fragments.label;
  const double far = cell_search_radius(reach, s), far2 = far * far;
  s.near.clear();
  for (const uint32_t e : scanned) {
    if (!cells.alive[e]) continue;
    const double dx = cells.x[e] - tip.x(), dy = cells.y[e] - tip.y(), dz = cells.z[e] - tip.z();
    const double d2 = dx * dx + dy * dy + dz * dz;
    if (!(d2 <= far2)) continue;
    const auto& nb = cells.neighbour[e];
    if (nb[0] != kNoSimplex && nb[1] != kNoSimplex && nb[2] != kNoSimplex && nb[3] != kNoSimplex)
      continue;  // inside its fragment
    if (held_fragment != kNoSimplex && e < label.size() && label[e] == held_fragment) continue;
    const double gap = std::sqrt(d2) - s.cell_radius_mm[e];
    if (gap > reach) continue;
    s.near.emplace_back(static_cast<float>(gap), e);
  }
  keep_nearest(s, t, [&](uint32_t e, uint32_t k) {
    t.sphere_x[k] = cells.x[e], t.sphere_y[k] = cells.y[e], t.sphere_z[k] = cells.z[e];
    t.sphere_r[k] = static_cast<float>(s.cell_radius_mm[e]);
    const double h = e < lf.lens.hardness.size() ? lf.lens.hardness[e] : settings.nucleus_hardness;
    t.sphere_k[k] = static_cast<float>(settings.stiffness_mn_mm * h / kStandardHardness);
  });
}

// The cells scan_lens_cells found near `tool` this frame (its entry then dropped), or, if it did
// not scan for it, a scan for this tip alone.
std::span<const uint32_t> take_scanned_cells(const SimplexCells& cells, Entity tool,
                                             const Vec3& tip, double far, HapticLensScratch& s) {
  for (size_t k = 0; k < s.scanned_tools.size(); ++k) {
    if (s.scanned_tools[k] != tool) continue;
    s.scanned_tools[k] = Entity{};
    return {s.scanned_cells[k].data(), s.scanned_count[k]};
  }
  std::vector<uint32_t>* out = &s.cells_scanned_alone;
  uint32_t count = 0;
  scan_cells(cells, {&tip, 1}, {&far, 1}, {&out, 1}, {&count, 1});
  return {s.cells_scanned_alone.data(), count};
}

}  // namespace

HapticLensSettings haptic_lens_settings(const Scene& scene) {
  HapticLensSettings s;
  s.reach_mm = scene.params.get("haptic_model.contact_radius_mm");
  s.stiffness_mn_mm = scene.params.get("haptic_model.lens_stiffness_mn_mm");
  s.cut_force_mn = scene.params.get("haptic_model.cut_force_mn");
  s.nucleus_hardness = scene.params.get("lens_model.nucleus_hardness");
  s.ultrasound_power = scene.params.get("lens_model.ultrasound_power");
  return s;
}

bool has_sculptable_lens(const Scene& scene) {
  const auto lens = scene.body(BodyPart::Lens);
  return lens && (scene.world.get<LensSculpting>(*lens) || scene.world.get<LensFragments>(*lens));
}

void scan_lens_cells(const Scene& scene, std::span<const Entity> tools,
                     std::span<const double> tip_radius_mm, const HapticLensSettings& settings,
                     HapticLensScratch& scratch) {
  scratch.scanned_tools.clear();
  const auto lens = scene.body(BodyPart::Lens);
  const LensFragments* lf = lens ? scene.world.get<LensFragments>(*lens) : nullptr;
  if (!lf || scene.world.get<LensSculpting>(*lens)) return;  // fill_lens_contacts's order
  size_cells(lf->lens.cells, scratch);
  std::array<Vec3, 8> tips;
  std::array<double, 8> far;
  std::array<std::vector<uint32_t>*, 8> out;
  const size_t k = std::min({tools.size(), tip_radius_mm.size(), tips.size()});
  if (scratch.scanned_cells.size() < k) scratch.scanned_cells.resize(k);
  scratch.scanned_count.assign(k, 0);
  for (size_t i = 0; i < k; ++i) {
    tips[i] = scene.world.get<ToolState>(tools[i])->pos;
    far[i] = cell_search_radius(tip_radius_mm[i] + settings.reach_mm, scratch);
    out[i] = &scratch.scanned_cells[i];
    scratch.scanned_tools.push_back(tools[i]);
  }
  scan_cells(lf->lens.cells, {tips.data(), k}, {far.data(), k}, {out.data(), k},
             {scratch.scanned_count.data(), k});
}

void fill_lens_contacts(const Scene& scene, Entity tool, const HapticLensSettings& settings,
                        HapticLensScratch& scratch, HapticTool& t) {
  t.sphere_count = 0;
  t.cut_force_mn = 0;
  t.held = {};
  const auto lens = scene.body(BodyPart::Lens);
  if (!lens) return;
  const ToolState& pose = *scene.world.get<ToolState>(tool);
  if (const HeldFragment* held = scene.world.get<HeldFragment>(tool); held && held->held)
    t.held = *held;
  const double reach = t.tip_radius_mm + settings.reach_mm;
  if (const LensSculpting* ls = scene.world.get<LensSculpting>(*lens)) {
    tet_spheres(scene, *ls, pose.pos, reach, settings, scratch, t);
  } else if (const LensFragments* lf = scene.world.get<LensFragments>(*lens)) {
    size_cells(lf->lens.cells, scratch);
    const std::span<const uint32_t> scanned = take_scanned_cells(
        lf->lens.cells, tool, pose.pos, cell_search_radius(reach, scratch), scratch);
    cell_spheres(*lf, pose.pos, reach, t.held.held ? t.held.fragment : kNoSimplex, scanned,
                 settings, scratch, t);
  } else {
    return;
  }
  // Seed 000 §5.3 / seed 002 §4: ultrasound at pedal 3 only (sculpt_radius_mm, ultrasound_power).
  const bool ultrasound =
      scene.world.get<Tool>(tool)->kind == ToolKind::PhacoProbe && pose.pedal >= 3.0;
  if (ultrasound) {
    t.cut_force_mn =
        static_cast<float>(settings.cut_force_mn * settings.nucleus_hardness / kStandardHardness /
                           std::max(0.25, settings.ultrasound_power));
  }
}

}  // namespace phaco
