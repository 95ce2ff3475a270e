#include "procedures/scene/lens_fragments.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <numbers>
#include <optional>

#include "components/from_mesh.hpp"
#include "components/held_fragment.hpp"
#include "components/particles.hpp"
#include "components/tets.hpp"
#include "components/tool.hpp"
#include "engine/core/error.hpp"
#include "procedures/lens/nucleus_groove.hpp"
#include "procedures/scene/capsule_physics.hpp"
#include "procedures/scene/density_units.hpp"
#include "procedures/scene/method_settings.hpp"
#include "procedures/scene/scene.hpp"

namespace phaco {
namespace {

constexpr double kRhexisRadiusMm = 2.6;
constexpr double kGrooveWidthTipDiameters = 1.5;  // the sculpting drill's trench (DESIGN.md §6)
constexpr double kGrooveDepthFraction = 0.8;

// The held fragment as the hand feels it (components/held_fragment.hpp; issue 19 item 5): its
// mass, its weight less buoyancy (the medium's reduced g), Stokes drag 6πμR of its equal-volume
// sphere in balanced salt solution (μ = 1 mPa·s = 1e-6 mN·s/mm²) and the occlusion's grip, the
// vacuum's pull on the port.
constexpr double kBssViscosityMnSPerMm2 = 1e-6;

HeldFragment held_load_of(const lens::FragmentLens& l, const lens::FragmentLensStats& st) {
  HeldFragment h;
  if (!st.held || l.held_fragment >= l.fragments.count) return h;
  const double m = l.fragments.mass[l.held_fragment];
  const double volume_mm3 = m / l.settings.density_kg_mm3;
  const double r = std::cbrt(3.0 * volume_mm3 / (4.0 * std::numbers::pi));
  h.held = true;
  h.fragment = l.held_fragment;
  h.mass_kg = static_cast<float>(m);
  h.drag_mn_s_per_mm = static_cast<float>(6.0 * std::numbers::pi * kBssViscosityMnSPerMm2 * r);
  // kg · mm/s² = mN.
  h.weight_mn = {0.0f, 0.0f, static_cast<float>(-m * l.settings.fluid.gravity_mm_s2)};
  h.hold_limit_mn =
      static_cast<float>(lens_tools::holding_force_mn(st.vacuum_mmhg, l.settings.fluid));
  return h;
}

uint32_t count_pieces(const lens::FragmentLens& l) {
  uint32_t n = 0;
  for (uint32_t f = 0; f < l.fragments.count; ++f)
    n += l.fragments.mass[f] >= kPieceMassFraction * l.initial_mass_kg;
  return n;
}

// The drill's start state: the cross-shaped groove removed (lens_fragments.hpp).
void groove(Scene& scene, LensFragments& lf, Tets& tets) {
  const eye::EyeParams& p = scene.params;
  lens::CrossGroove g;
  if (const auto& cross = scene.drill.guidance.trench_cross) {
    g.centre_mm = cross->centre_mm;
    g.first_angle_deg = cross->first_angle_deg;
    g.arm_length_mm = cross->arm_length_mm;
  }
  g.width_mm = kGrooveWidthTipDiameters * p.get("tools.phaco_tip_diameter_mm");
  g.depth_fraction = kGrooveDepthFraction;
  const double f = p.get("lens.nucleus_fraction");
  g.nucleus_radius_mm = f * 0.5 * p.get("lens.equatorial_diameter_mm");
  g.nucleus_anterior_mm = f * p.get("lens.anterior_half_thickness_mm");
  g.nucleus_posterior_mm = f * p.get("lens.posterior_half_thickness_mm");
  lens::FragmentLens& l = lf.lens;
  // In a procedure the groove is the trench the sculpting step cut (its tets are the cells).
  std::vector<uint32_t> cells;
  if (const auto& carried = scene.carried.lens_removed) {
    for (uint32_t c : *carried)
      if (c < l.cells.size() && l.cells.alive[c]) cells.push_back(c);
  } else {
    cells = lens::groove_cells(l.cells, g);
  }
  for (uint32_t c : cells) l.grooved_mass_kg += l.cells.mass[c];
  lens::FragmentLensStats st;
  lens::remove_lens_cells(l, cells, st);
  for (const auto& r : l.removals) table_remove(tets, r.cell);
  lf.grooved_volume_mm3 = l.volume_removed_mm3;
  double volume = 0;
  for (uint32_t c = 0; c < l.cells.size(); ++c)
    if (l.cells.alive[c]) volume += l.cells.volume[c];
  lf.start_volume_mm3 = volume;
  lf.pieces = lf.pieces_max = count_pieces(l);
}

}  // namespace

std::string lens_model(const Scene& scene) {
  return method_choice(scene, "lens.model", std::string(default_lens_model(scene.scenario.drill)));
}

void add_lens_fragments(Scene& scene) {
  for (const char* key : {"lens.broadphase", "lens.narrowphase"}) {
    if (scene.scenario.methods.count(key)) {
      throw InputError(scene.scenario.source + ": methods[\"" + key +
                       "\"]: applies to lens.model tets (tetrahedral sculpting), not fragments");
    }
  }
  const Entity e = *scene.body(BodyPart::Lens);
  const eye::EyeParams& params = scene.params;
  const TetMesh mesh = tet_mesh_of(scene.world.at<Particles>(e), scene.world.at<Tets>(e));

  lens::FragmentLensSettings s;
  // The nucleus_removal drill's bag is fitted through the equator: the capsular bag holds the lens
  // there, so cracked halves do not slide into the trench's gap down the slack of the containing
  // fit (constraints.hpp, CapFit).
  const lens_tools::CapFit fit = scene.scenario.drill == Drill::NucleusRemoval
                                     ? lens_tools::CapFit::ThroughEquator
                                     : lens_tools::CapFit::ContainsLens;
  const double a = 0.5 * params.get("lens.equatorial_diameter_mm");
  s.bounds = lens_tools::eye_bounds(a, params.get("lens.anterior_half_thickness_mm"),
                                    -params.get("lens.posterior_half_thickness_mm"),
                                    params.get("cornea.posterior_apex_z_mm"),
                                    params.get("cornea.posterior_radius_mm"),
                                    scene.carried.rhexis_radius_mm.value_or(kRhexisRadiusMm), fit);
  s.nucleus_hardness = std::min(1.0, params.get("lens_model.nucleus_hardness"));
  s.density_kg_mm3 = params.get("lens.density_kg_m3") * kKgPerMm3PerKgPerM3;
  double volume = 0;
  for (const auto& t : mesh.tets) {
    const Vec3 &p0 = mesh.vertices[t[0]], &p1 = mesh.vertices[t[1]], &p2 = mesh.vertices[t[2]],
               &p3 = mesh.vertices[t[3]];
    volume += (p1 - p0).dot((p2 - p0).cross(p3 - p0)) / 6.0;
  }
  // Contact support: 1.5 cell sizes, so neighbouring cells of two fragments overlap supports.
  s.contact.h = static_cast<float>(1.5 * std::cbrt(volume / std::max<size_t>(1, mesh.tets.size())));

  LensFragments lf;
  lf.nucleus_removal = scene.scenario.drill == Drill::NucleusRemoval;
  if (lf.nucleus_removal) {
    s.fluidics = true;
    s.fluid.vacuum_limit_mmhg = params.get("lens_model.vacuum_limit_mmhg");
    s.fluid.flow_ml_min = params.get("lens_model.aspiration_flow_ml_min");
    s.fluid.port_radius_mm = 0.5 * params.get("tools.phaco_tip_diameter_mm");
    s.fluid.gravity_mm_s2 = -s.medium.gravity.z();
    s.crack.strength_mn = params.get("lens_model.crack_strength_mn");
    s.crack.stiffness_mn_mm = params.get("haptic_model.lens_stiffness_mn_mm");
  }
  lf.lens = lens::make_fragment_lens(mesh, s);
  if (lf.nucleus_removal) groove(scene, lf, scene.world.at<Tets>(e));
  lf.rng = CounterRng(scene.scenario.seed, 5);
  lf.ultrasound_power = std::min(1.0, params.get("lens_model.ultrasound_power"));
  lf.previous_pose.resize(scene.tools.size());
  for (size_t i = 0; i < scene.tools.size(); ++i) {
    lf.previous_pose[i] = scene.world.at<ToolState>(scene.tools[i]);
    // The probe carries what it holds, for the haptic thread (haptic_publish reads it).
    if (lf.nucleus_removal && scene.world.at<Tool>(scene.tools[i]).kind == ToolKind::PhacoProbe)
      scene.world.add(scene.tools[i], HeldFragment{});
  }
  scene.world.name_component<LensFragments>("cells");
  scene.world.add(e, std::move(lf));
}

SystemDesc lens_fragments_system(Scene& scene) {
  const Entity e = *scene.body(BodyPart::Lens);
  std::vector<std::string> writes = {"lens.cells", "lens.tets"};
  if (scene.world.at<LensFragments>(e).nucleus_removal) writes.push_back("tools.held");
  return {.name = "lens_fragments",
          .phase = Phase::Dynamics,
          .reads = {"tools.pose"},
          .writes = std::move(writes),
          .run = [&scene, e](const FrameContext& ctx) {
            LensFragments& lf = scene.world.at<LensFragments>(e);
            lens::LensTools tools;
            double power = 0;
            std::optional<Entity> probe;
            for (size_t i = 0; i < scene.tools.size(); ++i) {
              const Entity te = scene.tools[i];
              const ToolState& pose = scene.world.at<ToolState>(te);
              switch (scene.world.at<Tool>(te).kind) {
                case ToolKind::PhacoProbe: {
                  probe = te;
                  power = lens_tools::ultrasound_power(pose.pedal, lf.ultrasound_power);
                  if (power > 0) tools.phaco = lens_tools::phaco_tip(pose, lf.ultrasound_power);
                  if (pose.pedal >= 2.0)
                    tools.aspirator = lens_tools::Aspirator{pose.pos, lf.vacuum_mmhg};
                  tools.probe_tip = pose.pos;
                  tools.probe_velocity = (pose.pos - lf.previous_pose[i].pos) / ctx.dt_s;
                  tools.aspirating = pose.pedal >= 2.0;
                  break;
                }
                case ToolKind::Chopper:
                  tools.chopper_tip = pose.pos;
                  break;
                case ToolKind::Aspirator:
                  if (pose.pedal >= 2.0)
                    tools.aspirator = lens_tools::Aspirator{pose.pos, lf.vacuum_mmhg};
                  break;
                case ToolKind::Hook:
                  tools.hook = lens_tools::hook_from_poses(pose, lf.previous_pose[i], ctx.dt_s,
                                                           lf.lens.settings.hook);
                  break;
                default:
                  break;
              }
              lf.previous_pose[i] = pose;
            }
            const auto t0 = std::chrono::steady_clock::now();
            const uint64_t removed_before = lf.lens.cells_removed;
            const lens::FragmentLensStats st =
                lens::step_fragment_lens(lf.lens, tools, lf.rng, ctx.frame, ctx.dt_s);
            if (lf.nucleus_removal) {
              lf.cde_pct_s += 100.0 * power * ctx.dt_s;
              lf.ultrasound_time_s += power > 0 ? ctx.dt_s : 0.0;
              lf.aspiration_time_s += tools.aspirating ? ctx.dt_s : 0.0;
              lf.occluded_time_s += st.occluded ? ctx.dt_s : 0.0;
              lf.held_time_s += st.held ? ctx.dt_s : 0.0;
              lf.max_vacuum_mmhg = std::max(lf.max_vacuum_mmhg, st.vacuum_mmhg);
              if (st.push.engaged) {
                lf.chopper_force_max_mn = std::max(lf.chopper_force_max_mn, st.push.force_mn);
                lf.chopper_force_sum_mn += st.push.force_mn;
                ++lf.chopper_engaged_frames;
              }
              lf.pieces = count_pieces(lf.lens);
              lf.pieces_max = std::max(lf.pieces_max, lf.pieces);
              if (probe) scene.world.at<HeldFragment>(*probe) = held_load_of(lf.lens, st);
            }
            const double ms =
                std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0)
                    .count();
            lf.ms_total += ms, lf.ms_max = std::max(lf.ms_max, ms);
            lf.contact_pairs_total += st.contact_pairs;
            lf.contact_pairs_max = std::max(lf.contact_pairs_max, st.contact_pairs);
            if (lf.lens.awake) ++lf.frames_awake;
            if (lf.lens.cells_removed != removed_before) {
              Tets& tets = scene.world.at<Tets>(e);
              for (const auto& r : lf.lens.removals) table_remove(tets, r.cell);
            }
          }};
}

nlohmann::json lens_fragments_summary(Scene& scene) {
  const auto e = scene.body(BodyPart::Lens);
  if (!e) return nullptr;
  const LensFragments* lf = scene.world.get<LensFragments>(*e);
  if (!lf) return nullptr;
  const lens::FragmentLens& l = lf->lens;
  nlohmann::json j;
  j["model"] = "fragments";
  j["cells"] = l.cells.size();
  j["cells_removed"] = l.cells_removed;
  j["cells_aspirated"] = l.cells_aspirated;
  j["volume_removed_mm3"] = l.volume_removed_mm3;
  j["fragments"] = l.fragments.count;
  j["max_fragments"] = l.max_fragments;
  j["frames_awake"] = lf->frames_awake;
  j["step_ms_mean"] = scene.frame ? lf->ms_total / double(scene.frame) : 0.0;
  j["step_ms_max"] = lf->ms_max;
  j["contact_pairs_mean"] =
      scene.frame ? double(lf->contact_pairs_total) / double(scene.frame) : 0.0;
  j["contact_pairs_max"] = lf->contact_pairs_max;
  bool finite = true;
  for (uint32_t c = 0; c < l.cells.size(); ++c)
    if (l.cells.alive[c])
      finite &=
          std::isfinite(l.cells.x[c]) && std::isfinite(l.cells.y[c]) && std::isfinite(l.cells.z[c]);
  j["finite"] = finite;
  if (lf->nucleus_removal) {
    j["cracks"] = l.cracks;
    j["links_broken"] = l.links_broken;
    j["grooved_volume_mm3"] = lf->grooved_volume_mm3;
    j["occluded_time_s"] = lf->occluded_time_s;
    j["held_time_s"] = lf->held_time_s;
    j["max_vacuum_mmhg"] = lf->max_vacuum_mmhg;
    j["mass_kg"] = {{"initial", l.initial_mass_kg},
                    {"alive", lens::alive_mass_kg(l)},
                    {"emulsified", l.emulsified_mass_kg},
                    {"aspirated", l.aspirated_mass_kg},
                    {"grooved", l.grooved_mass_kg}};
  }
  return j;
}

}  // namespace phaco
