#include "procedures/scene/lens_fragments.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>

#include "components/from_mesh.hpp"
#include "components/particles.hpp"
#include "components/tets.hpp"
#include "components/tool.hpp"
#include "engine/core/error.hpp"
#include "procedures/scene/capsule_physics.hpp"
#include "procedures/scene/scene.hpp"

namespace phaco {
namespace {

constexpr double kKgPerMm3PerKgPerM3 = 1e-9;
constexpr double kRhexisRadiusMm = 2.6;

}  // namespace

std::string lens_model(const Scene& scene) {
  return method_choice(scene, "lens.model", "tets");
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
  const double a = 0.5 * params.get("lens.equatorial_diameter_mm");
  s.bounds = lens_tools::eye_bounds(a, params.get("lens.anterior_half_thickness_mm"),
                                    -params.get("lens.posterior_half_thickness_mm"),
                                    params.get("cornea.posterior_apex_z_mm"),
                                    params.get("cornea.posterior_radius_mm"), kRhexisRadiusMm);
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
  lf.lens = lens::make_fragment_lens(mesh, s);
  lf.rng = CounterRng(scene.scenario.seed, 5);
  lf.ultrasound_power = std::min(1.0, params.get("lens_model.ultrasound_power"));
  lf.previous_pose.resize(scene.tools.size());
  for (size_t i = 0; i < scene.tools.size(); ++i)
    lf.previous_pose[i] = scene.world.at<ToolState>(scene.tools[i]);
  scene.world.name_component<LensFragments>("cells");
  scene.world.add(e, std::move(lf));
}

SystemDesc lens_fragments_system(Scene& scene) {
  const Entity e = *scene.body(BodyPart::Lens);
  return {.name = "lens_fragments",
          .phase = Phase::Dynamics,
          .reads = {"tools.pose"},
          .writes = {"lens.cells", "lens.tets"},
          .run = [&scene, e](const FrameContext& ctx) {
            LensFragments& lf = scene.world.at<LensFragments>(e);
            lens::LensTools tools;
            for (size_t i = 0; i < scene.tools.size(); ++i) {
              const Entity te = scene.tools[i];
              const ToolState& pose = scene.world.at<ToolState>(te);
              switch (scene.world.at<Tool>(te).kind) {
                case ToolKind::PhacoProbe: {
                  const double power =
                      lens_tools::ultrasound_power(pose.pedal, lf.ultrasound_power);
                  if (power > 0) tools.phaco = lens_tools::phaco_tip(pose, lf.ultrasound_power);
                  if (pose.pedal >= 2.0)
                    tools.aspirator = lens_tools::Aspirator{pose.pos, lf.vacuum_mmhg};
                  break;
                }
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
            lens::step_fragment_lens(lf.lens, tools, lf.rng, ctx.frame, ctx.dt_s);
            const double ms =
                std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0)
                    .count();
            lf.ms_total += ms, lf.ms_max = std::max(lf.ms_max, ms);
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
  bool finite = true;
  for (uint32_t c = 0; c < l.cells.size(); ++c)
    if (l.cells.alive[c])
      finite &=
          std::isfinite(l.cells.x[c]) && std::isfinite(l.cells.y[c]) && std::isfinite(l.cells.z[c]);
  j["finite"] = finite;
  return j;
}

}  // namespace phaco
