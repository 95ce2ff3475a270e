#include "procedures/scene/lens_sculpting.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <numbers>

#include "components/from_mesh.hpp"
#include "components/particles.hpp"
#include "components/tets.hpp"
#include "components/tool.hpp"
#include "engine/core/error.hpp"
#include "procedures/scene/capsule_physics.hpp"
#include "procedures/scene/density_units.hpp"
#include "procedures/scene/scene.hpp"

namespace phaco {
namespace {

Vec3 rotate_z(const Vec3& p, double angle) {
  const double c = std::cos(angle), s = std::sin(angle);
  return {c * p.x() - s * p.y(), s * p.x() + c * p.y(), p.z()};
}

// The alive tets' centres in the probe's tip sphere (lens frame): the trench wall the tip meets.
// Centres, as the seed's sculpting test (§5.3): the wall is where the sculpting stopped.
void wall_in_tip(LensSculpting& ls, const Vec3& tip_local, double radius) {
  const sculpt::TipCapsule tip{tip_local, tip_local, radius};
  auto& cand = ls.sculpt.candidates;
  cand.clear();
  sculpt::BroadphaseStats stats;
  if (ls.sculpt.options.broadphase == sculpt::Broadphase::Octree) {
    sculpt::octree_candidates(ls.sculpt.octree, ls.topology, tip, ls.sculpt.tree_queue, cand,
                              stats);
  } else {
    ls.sculpt.dbvt.candidates(ls.topology, tip, cand, stats);
  }
  ls.wall.clear();
  const double r2 = radius * radius;
  for (uint32_t t : cand) {
    if (!ls.topology.alive[t]) continue;
    const Vec3 c = sculpt::tet_centre(ls.topology, t);
    if ((c - tip_local).squaredNorm() < r2) ls.wall.push_back(c);
  }
}

// The probe's angle about the optical axis (world), rad.
double probe_azimuth(const Vec3& p) {
  return std::atan2(p.y(), p.x());
}

// The scene's lens particles: the rest vertices turned by the nucleus angle.
void place_lens(const LensSculpting& ls, Particles& p) {
  const double c = std::cos(ls.rotation.angle_rad), s = std::sin(ls.rotation.angle_rad);
  for (size_t i = 0; i < ls.rest.size(); ++i) {
    const Vec3& r = ls.rest[i];
    p.x[i] = static_cast<float>(c * r.x() - s * r.y());
    p.y[i] = static_cast<float>(s * r.x() + c * r.y());
  }
}

}  // namespace

void add_lens_sculpting(Scene& scene) {
  const Entity lens = *scene.body(BodyPart::Lens);
  const Particles& p = scene.world.at<Particles>(lens);
  const Tets& tets = scene.world.at<Tets>(lens);
  const eye::EyeParams& params = scene.params;

  const std::string broadphase = method_choice(scene, "lens.broadphase", "octree");
  const std::string narrowphase = method_choice(scene, "lens.narrowphase", "centre");

  LensSculpting ls;
  TetMesh mesh = tet_mesh_of(p, tets);
  ls.topology = build_tet_topology(mesh);
  ls.rest = std::move(mesh.vertices);

  sculpt::SculptOptions options;
  options.broadphase = broadphase == "dbvt" ? sculpt::Broadphase::Dbvt : sculpt::Broadphase::Octree;
  options.narrowphase = narrowphase == "exact_gjk"   ? sculpt::Narrowphase::ExactGjk
                        : narrowphase == "exact_mpr" ? sculpt::Narrowphase::ExactMpr
                                                     : sculpt::Narrowphase::CentreInSphere;
  ls.sculpt = sculpt::make_sculpt_state(ls.topology, options);

  // Seed 000 §5.4: every tet a point mass of equal weight; the lens's mass from its volume.
  double volume = 0;
  std::vector<Vec3> centres(ls.topology.tet_count);
  for (uint32_t t = 0; t < ls.topology.tet_count; ++t) {
    volume += ls.topology.volume[t];
    centres[t] = sculpt::tet_centre(ls.topology, t);
  }
  const double lens_mass = volume * params.get("lens.density_kg_m3") * kKgPerMm3PerKgPerM3;
  ls.rotation =
      nucleus::make_rotation(centres, lens_mass / std::max<uint32_t>(1, ls.topology.tet_count));
  ls.push.friction_torque = params.get("lens_model.damping_torque_mn_mm");
  ls.push.damping = params.get("lens_model.bag_damping_mn_mm_s");
  ls.ultrasound_power = params.get("lens_model.ultrasound_power");
  if (ls.ultrasound_power > 1.0) {
    throw InputError(scene.scenario.source +
                     ": eye lens_model.ultrasound_power must be in (0, 1], got " +
                     std::to_string(ls.ultrasound_power));
  }
  // A harder nucleus yields less to the same ultrasound (issue 7's difficulty, docs/drills.md):
  // above the standard hardness 0.5 the effective power falls as 0.5 / hardness (a brunescent
  // nucleus, hardness 1, takes half the power's reach); softer nuclei cannot exceed the set power.
  ls.ultrasound_power *=
      std::min(1.0, kStandardHardness / params.get("lens_model.nucleus_hardness"));
  const double f = params.get("lens.nucleus_fraction");
  ls.nucleus = {f * 0.5 * params.get("lens.equatorial_diameter_mm"),
                f * params.get("lens.anterior_half_thickness_mm"),
                -f * params.get("lens.posterior_half_thickness_mm")};
  scene.world.name_component<LensSculpting>("sculpting");
  scene.world.add(lens, std::move(ls));
}

SystemDesc lens_sculpt_system(Scene& scene) {
  const Entity lens = *scene.body(BodyPart::Lens);
  return {.name = "lens_sculpt",
          .phase = Phase::Topology,
          .reads = {"tools.pose"},
          .writes = {"lens.tets", "lens.particles", "lens.sculpting"},
          .run = [&scene, lens](const FrameContext& ctx) {
            LensSculpting& ls = scene.world.at<LensSculpting>(lens);
            const double angle0 = ls.rotation.angle_rad;
            // The bag's friction and damping first: what the nucleus turns on its own this step.
            const double free_turn = nucleus::free_rotation_step(ls.rotation, ls.push, ctx.dt_s);
            for (Entity e : scene.tools) {
              if (scene.world.at<Tool>(e).kind != ToolKind::PhacoProbe) continue;
              const ToolState& tool = scene.world.at<ToolState>(e);
              const Vec3 tip = rotate_z(tool.pos, -ls.rotation.angle_rad);  // into the lens frame
              const double radius = sculpt::sculpt_radius_mm(tool.pedal, ls.ultrasound_power);
              if (radius > 0) {
                if (!ls.ultrasound_was_on) ++ls.strokes, ls.previous_tip.reset();
                ls.ultrasound_was_on = true;
                ls.ultrasound_time_s += ctx.dt_s;
                ls.previous_probe.reset();
                const auto t0 = std::chrono::steady_clock::now();
                const auto removed = sculpt::sculpt_step(
                    ls.topology, ls.rest, ls.sculpt, {tip, ls.previous_tip.value_or(tip), radius});
                const double ms =
                    std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0)
                        .count();
                ls.previous_tip = tip;
                ++ls.sculpt_steps;
                ls.sculpt_ms_total += ms, ls.sculpt_ms_max = std::max(ls.sculpt_ms_max, ms);
                ls.max_removed_per_step =
                    std::max<uint32_t>(ls.max_removed_per_step, uint32_t(removed.size()));
                if (removed.empty()) continue;
                Tets& tets = scene.world.at<Tets>(lens);
                std::vector<Vec3> centres;
                centres.reserve(removed.size());
                for (uint32_t t : removed) {
                  table_remove(tets, t);
                  const Vec3 c = sculpt::tet_centre(ls.topology, t);
                  centres.push_back(c);
                  ls.removed.push_back({c, ls.topology.volume[t], ls.strokes - 1});
                  ls.volume_removed_mm3 += ls.topology.volume[t];
                }
                nucleus::remove_tets(ls.rotation, centres);
                continue;
              }
              ls.ultrasound_was_on = false;
              ls.previous_tip.reset();
              // No ultrasound: the tip pushes the trench wall ahead of it, which cannot pass it
              // (systems/nucleus/rotation.hpp): the nucleus turns by the least angle that keeps
              // the wall at the tip, at most the tip's own travel about the axis relative to it.
              const double rho = std::hypot(tool.pos.x(), tool.pos.y());
              if (ls.previous_probe && rho > sculpt::kPhacoTipRadiusMm) {
                const double travel =
                    std::remainder(probe_azimuth(tool.pos) - probe_azimuth(*ls.previous_probe),
                                   2 * std::numbers::pi) -
                    free_turn;
                const int sign = travel > 0 ? 1 : travel < 0 ? -1 : 0;
                if (sign != 0) {
                  wall_in_tip(ls, tip, sculpt::kPhacoTipRadiusMm);
                  const double need =
                      nucleus::wall_clearance_angle(ls.wall, tip, sculpt::kPhacoTipRadiusMm, sign);
                  const double turn = std::min(need, std::abs(travel));
                  if (turn > 0) {
                    nucleus::contact_rotation_step(ls.rotation, turn, sign, ctx.dt_s);
                    ++ls.push_frames;
                  }
                }
              }
              ls.previous_probe = tool.pos;
            }
            if (ls.rotation.angle_rad != angle0) place_lens(ls, scene.world.at<Particles>(lens));
          }};
}

lens::TrenchReport lens_trenches(const Scene& scene) {
  const auto lens = scene.body(BodyPart::Lens);
  if (!lens) return {};
  const LensSculpting* ls = scene.world.get<LensSculpting>(*lens);
  if (!ls) return {};
  return lens::measure_trenches(ls->removed, ls->nucleus);
}

nlohmann::json lens_sculpting_summary(Scene& scene) {
  const auto lens = scene.body(BodyPart::Lens);
  if (!lens) return nullptr;
  const LensSculpting* ls = scene.world.get<LensSculpting>(*lens);
  if (!ls) return nullptr;
  nlohmann::json j;
  j["broadphase"] = sculpt::to_string(ls->sculpt.options.broadphase);
  j["narrowphase"] = sculpt::to_string(ls->sculpt.options.narrowphase);
  j["tets"] = ls->topology.tet_count;
  j["tets_removed"] = ls->topology.tet_count - ls->topology.alive_count;
  j["surface_tets"] = ls->topology.surface.size();
  j["volume_removed_mm3"] = ls->volume_removed_mm3;
  j["ultrasound_time_s"] = ls->ultrasound_time_s;
  j["strokes"] = ls->strokes;
  j["sculpt_steps"] = ls->sculpt_steps;
  j["sculpt_ms_mean"] = ls->sculpt_steps ? ls->sculpt_ms_total / double(ls->sculpt_steps) : 0.0;
  j["sculpt_ms_max"] = ls->sculpt_ms_max;
  j["max_tets_removed_per_step"] = ls->max_removed_per_step;
  j["nucleus_rotation_deg"] = ls->rotation.angle_rad * 180.0 / std::numbers::pi;
  j["nucleus_inertia_kg_mm2"] = ls->rotation.inertia;
  j["nucleus_inertia0_kg_mm2"] = ls->rotation.inertia0;
  j["push_frames"] = ls->push_frames;
  j["nucleus_push_torque_max_mn_mm"] = ls->rotation.contact_torque_max;
  const lens::TrenchReport trenches = lens::measure_trenches(ls->removed, ls->nucleus);
  j["trench_count"] = trenches.trenches.size();
  j["trench_crossing_angle_deg"] = trenches.crossing_angle_deg;
  nlohmann::json list = nlohmann::json::array();
  for (const lens::Trench& t : trenches.trenches) {
    list.push_back({{"width_mm", t.width_mm},
                    {"depth_mm", t.depth_mm},
                    {"depth_fraction", t.depth_fraction},
                    {"length_mm", t.length_mm},
                    {"volume_mm3", t.volume_mm3},
                    {"axis_deg", std::atan2(t.axis.y(), t.axis.x()) * 180.0 / std::numbers::pi},
                    {"strokes", t.strokes.size()}});
  }
  j["trenches"] = list;
  return j;
}

}  // namespace phaco
