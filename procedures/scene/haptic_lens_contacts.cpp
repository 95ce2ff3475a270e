#include "procedures/scene/haptic_lens_contacts.hpp"

#include <algorithm>
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

// Fragment lens (seed 002 §4): alive cells with an external face, less the held fragment's.
void cell_spheres(const LensFragments& lf, const Vec3& tip, double reach, uint32_t held_fragment,
                  const HapticLensSettings& settings, HapticLensScratch& s, HapticTool& t) {
  const SimplexCells& cells = lf.lens.cells;
  const std::vector<uint32_t>& label = lf.lens.fragments.label;
  if (s.cells_of != cells.size()) {  // once per lens: a cell's volume never changes
    s.max_cell_radius_mm = 0.0;
    for (uint32_t e = 0; e < cells.size(); ++e)
      s.max_cell_radius_mm = std::max(s.max_cell_radius_mm, equal_volume_radius(cells.volume[e]));
    s.cells_of = cells.size();
  }
  // A cell with its gap within the reach has its centre within reach + its radius: the cheap
  // distance test first, the cube root only for those (the same cells pass as without it).
  const double far = reach + s.max_cell_radius_mm + 1e-6, far2 = far * far;
  // Before that test, a float one over blocks of the position columns, which the compiler
  // vectorises: this scan runs per tool every frame the haptic thread is beside the simulation, in
  // series after the lens step (level 3: 52k cells, most of them far). It only drops cells beyond
  // far + kHapticScanMarginMm, far more than float rounding at lens coordinates (~1e-6 mm), so the
  // cells the double test keeps are the same, in the same order.
  const float tx = static_cast<float>(tip.x()), ty = static_cast<float>(tip.y()),
              tz = static_cast<float>(tip.z());
  const float ff = static_cast<float>(far + kHapticScanMarginMm), ff2 = ff * ff;
  const float* X = cells.x.data();
  const float* Y = cells.y.data();
  const float* Z = cells.z.data();
  const auto n = static_cast<uint32_t>(cells.size());
  s.near.clear();
  for (uint32_t b = 0; b < n; b += kHapticScanBlock) {
    const uint32_t m = std::min(kHapticScanBlock, n - b);
    uint8_t hit[kHapticScanBlock];
    uint8_t any = 0;
    for (uint32_t i = 0; i < m; ++i) {
      const float dx = X[b + i] - tx, dy = Y[b + i] - ty, dz = Z[b + i] - tz;
      hit[i] = dx * dx + dy * dy + dz * dz <= ff2;
      any |= hit[i];
    }
    if (!any) continue;
    for (uint32_t i = 0; i < m; ++i) {
      if (!hit[i]) continue;
      const uint32_t e = b + i;
      if (!cells.alive[e]) continue;
      {
        const double dx = cells.x[e] - tip.x(), dy = cells.y[e] - tip.y(),
                     dz = cells.z[e] - tip.z();
        if (!(dx * dx + dy * dy + dz * dz <= far2)) continue;
      }
      const auto& nb = cells.neighbour[e];
      if (nb[0] != kNoSimplex && nb[1] != kNoSimplex && nb[2] != kNoSimplex && nb[3] != kNoSimplex)
        continue;  // inside its fragment
      if (held_fragment != kNoSimplex && e < label.size() && label[e] == held_fragment) continue;
      const double dx = cells.x[e] - tip.x(), dy = cells.y[e] - tip.y(), dz = cells.z[e] - tip.z();
      const double gap =
          std::sqrt(dx * dx + dy * dy + dz * dz) - equal_volume_radius(cells.volume[e]);
      if (gap > reach) continue;
      s.near.emplace_back(static_cast<float>(gap), e);
    }
  }
  keep_nearest(s, t, [&](uint32_t e, uint32_t k) {
    t.sphere_x[k] = cells.x[e], t.sphere_y[k] = cells.y[e], t.sphere_z[k] = cells.z[e];
    t.sphere_r[k] = static_cast<float>(equal_volume_radius(cells.volume[e]));
    const double h = e < lf.lens.hardness.size() ? lf.lens.hardness[e] : settings.nucleus_hardness;
    t.sphere_k[k] = static_cast<float>(settings.stiffness_mn_mm * h / kStandardHardness);
  });
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
    cell_spheres(*lf, pose.pos, reach, t.held.held ? t.held.fragment : kNoSimplex, settings,
                 scratch, t);
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
