#include "procedures/scene/nucleus_removal_metrics.hpp"

#include <algorithm>
#include <cmath>

#include "components/tool.hpp"
#include "procedures/scene/lens_fragments.hpp"
#include "procedures/scene/scene.hpp"

namespace phaco {

namespace {

const LensFragments* fragments_of(const Scene& scene) {
  const auto lens = scene.body(BodyPart::Lens);
  return lens ? scene.world.get<LensFragments>(*lens) : nullptr;
}

bool is_tip(ToolKind k) {
  return k == ToolKind::PhacoProbe || k == ToolKind::Chopper;
}

}  // namespace

double posterior_capsule_distance_mm(const NucleusRemovalRecord& r, const Vec3& p) {
  if (p.z() <= r.rim_z_mm) {
    const auto& post = r.bounds.posterior_capsule;
    return post.radius_mm - (p - post.centre).norm();
  }
  return std::hypot(std::hypot(p.x(), p.y()) - r.rim_radius_mm, p.z() - r.rim_z_mm);
}

NucleusRemovalRecord make_nucleus_removal_record(const Scene& scene) {
  NucleusRemovalRecord r;
  if (const LensFragments* lf = fragments_of(scene)) r.bounds = lf->lens.settings.bounds;
  r.pupil_radius_mm = 0.5 * scene.params.get("iris.pupil_diameter_mm");
  // The rim: both spheres are centred on the optical axis, R1² − (z − c1)² = R2² − (z − c2)².
  const auto& a = r.bounds.anterior_capsule;
  const auto& b = r.bounds.posterior_capsule;
  const double c1 = a.centre.z(), c2 = b.centre.z();
  if (c1 != c2) {
    r.rim_z_mm = (a.radius_mm * a.radius_mm - b.radius_mm * b.radius_mm + c2 * c2 - c1 * c1) /
                 (2 * (c2 - c1));
    r.rim_radius_mm =
        std::sqrt(std::max(0.0, b.radius_mm * b.radius_mm - (r.rim_z_mm - c2) * (r.rim_z_mm - c2)));
  }
  r.through.assign(scene.tools.size(), 0);
  r.entry.assign(scene.tools.size(), Vec3::Zero());
  r.entered.assign(scene.tools.size(), 0);
  r.wound_radius_mm = scene.params.get("tools.keratome_width_mm");
  return r;
}

uint32_t sample_nucleus_removal(Scene& scene, NucleusRemovalRecord& r, double dt_s) {
  uint32_t ruptured = 0;
  bool near = false;
  for (size_t i = 0; i < scene.tools.size(); ++i) {
    const Entity e = scene.tools[i];
    if (!is_tip(scene.world.at<Tool>(e).kind)) continue;
    const Vec3 p = scene.world.at<ToolState>(e).pos;
    const double d = posterior_capsule_distance_mm(r, p);
    r.posterior_min_distance_mm = std::min(r.posterior_min_distance_mm, d);
    const bool through = d < 0;
    if (through && !r.through[i]) ruptured |= 1u << i, r.ruptured = true;
    r.through[i] = through;
    const auto& cornea = r.bounds.cornea;
    const double de = cornea.radius_mm - (p - cornea.centre).norm();
    if (!r.entered[i] && de > 0) r.entered[i] = 1, r.entry[i] = p;
    const bool in_wound = r.entered[i] && (p - r.entry[i]).norm() <= r.wound_radius_mm;
    if (std::hypot(p.x(), p.y()) < r.pupil_radius_mm && de > 0 && !in_wound) {
      r.endothelium_min_distance_mm = std::min(r.endothelium_min_distance_mm, de);
      near |= de < kEndotheliumNearMm;
    }
  }
  if (near) r.endothelium_near_s += dt_s;
  // Pieces out of the bag (not the held one).
  const LensFragments* lf = fragments_of(scene);
  if (!lf) return ruptured;
  const lens::FragmentLens& l = lf->lens;
  const uint32_t nf = l.fragments.count;
  r.fx.assign(nf, 0.0), r.fy.assign(nf, 0.0), r.fz.assign(nf, 0.0);
  uint32_t out = 0;
  const auto& ant = r.bounds.anterior_capsule;
  for (uint32_t f = 0; f < nf; ++f) {
    const double m = l.fragments.mass[f];
    if (f == l.held_fragment || m < kPieceMassFraction * l.initial_mass_kg) continue;
    // The pieces' centres only, over their members (alive, ascending ids).
    for (uint32_t k = l.fragments.offsets[f]; k < l.fragments.offsets[f + 1]; ++k) {
      const uint32_t c = l.fragments.members[k];
      const double mc = l.cells.mass[c];
      r.fx[f] += mc * l.cells.x[c], r.fy[f] += mc * l.cells.y[c], r.fz[f] += mc * l.cells.z[c];
    }
    const Vec3 c(r.fx[f] / m, r.fy[f] / m, r.fz[f] / m);
    out += (c - ant.centre).norm() > ant.radius_mm;
  }
  r.anterior_chamber_max = std::max(r.anterior_chamber_max, out);
  return ruptured;
}

void nucleus_removal_metrics(Scene& scene, const NucleusRemovalRecord& r, nlohmann::json& m) {
  const LensFragments* lf = fragments_of(scene);
  if (!lf) return;
  const lens::FragmentLens& l = lf->lens;
  const double removed = l.volume_removed_mm3 - lf->grooved_volume_mm3;
  m["fragments_removed"] = lf->pieces_max - lf->pieces;
  m["fragments_left"] = lf->pieces;
  m["cracks"] = l.cracks;
  m["volume_removed_mm3"] = removed;
  m["volume_removed_fraction"] = lf->start_volume_mm3 > 0 ? removed / lf->start_volume_mm3 : 0.0;
  m["cde_pct_s"] = lf->cde_pct_s;
  m["ultrasound_time_s"] = lf->ultrasound_time_s;
  m["aspiration_time_s"] = lf->aspiration_time_s;
  m["occlusion_time_s"] = lf->occluded_time_s;
  m["max_vacuum_mmHg"] = lf->max_vacuum_mmhg;
  m["chopper_force_mN.max"] = lf->chopper_force_max_mn;
  m["chopper_force_mN.mean"] = lf->chopper_engaged_frames
                                   ? lf->chopper_force_sum_mn / double(lf->chopper_engaged_frames)
                                   : 0.0;
  if (std::isfinite(r.posterior_min_distance_mm))
    m["posterior_capsule.min_distance_mm"] = r.posterior_min_distance_mm;
  m["posterior_capsule.rupture"] = r.ruptured ? 1 : 0;
  if (std::isfinite(r.endothelium_min_distance_mm))
    m["endothelium.min_distance_mm"] = r.endothelium_min_distance_mm;
  m["endothelium.time_within_1mm_s"] = r.endothelium_near_s;
  m["anterior_chamber_fragments.max"] = r.anterior_chamber_max;
}

}  // namespace phaco
