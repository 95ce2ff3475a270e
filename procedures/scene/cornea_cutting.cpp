#include "procedures/scene/cornea_cutting.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <numbers>
#include <vector>

#include "components/particles.hpp"
#include "components/tool.hpp"
#include "components/triangles.hpp"
#include "procedures/incision/cornea_sheet.hpp"
#include "procedures/incision/cut_measure.hpp"
#include "procedures/incision/surface_cutter.hpp"
#include "procedures/scene/drill_metrics.hpp"
#include "procedures/scene/scene.hpp"
#include "systems/springs/springs.hpp"

namespace phaco {

namespace {

// The tip more than this behind the furthest it reached along the blade axis while cutting is a
// withdrawal. A hand's tremor (RMS 13–21 µm along the shaft at 8–12 Hz, issue 20 item 4) moves the
// blade back and forth by less; the 1 nm per frame this was ended the cut on the first tremor.
constexpr double kWithdrawMm = 0.1;
constexpr double kRadToDeg = 180.0 / std::numbers::pi;

// The blade stopped: waiting ends finished, tips kept, paths ended.
void end_paths(cut::CutMesh& m, CorneaCutting& cc) {
  for (corneal_incision::SurfaceCutter* s : {&cc.outer, &cc.inner}) {
    if (cc.finish_min_angle_deg > 0.0) {
      corneal_incision::finish_surface(m, *s, cc.cut, cc.finish_min_angle_deg, cc.log, cc.segments);
    }
    for (int k = 0; k < 2; ++k) {
      s->tips[k] = corneal_incision::live_tip(m, s->side[k].path);
      cut::end_cut(s->side[k].path);
    }
  }
  cc.done = true;
  cc.cutting = false;
}

CorneaCutting* cutting_of(Scene& scene) {
  const auto cornea = scene.body(BodyPart::Cornea);
  return cornea ? scene.world.get<CorneaCutting>(*cornea) : nullptr;
}

cut::CutMesh mesh_of(Scene& scene, CorneaCutting& cc) {
  const Entity cornea = *scene.body(BodyPart::Cornea);
  return {scene.world.at<Particles>(cornea), scene.world.at<Triangles>(cornea), cc.springs,
          cc.topology, cc.material};
}

nlohmann::json lip_series(const cut::CutMesh& m, const incision::CorneaSpheres& s,
                          corneal_incision::Surface surface) {
  std::vector<std::array<uint32_t, 2>> edges;
  corneal_incision::lip_edges(m, s, surface, edges);
  nlohmann::json out = nlohmann::json::array();
  for (const auto& e : edges) {
    const Vec3 a = cut::particle_position(m.particles, e[0]);
    const Vec3 b = cut::particle_position(m.particles, e[1]);
    out.push_back({{a.x(), a.y(), a.z()}, {b.x(), b.y(), b.z()}});
  }
  return out;
}

}  // namespace

bool add_cornea_cutting(Scene& scene) {
  const auto cornea = scene.body(BodyPart::Cornea);
  if (!cornea) return false;
  std::optional<Entity> keratome;
  for (Entity t : scene.tools) {
    if (scene.world.at<Tool>(t).kind == ToolKind::Keratome) {
      keratome = t;
      break;
    }
  }
  if (!keratome) return false;
  Particles& p = scene.world.at<Particles>(*cornea);
  Triangles& tr = scene.world.at<Triangles>(*cornea);
  CorneaCutting cc;
  cc.keratome = *keratome;
  cc.spheres = corneal_incision::cornea_spheres(scene.params);
  cc.shape = corneal_incision::eye_keratome(scene.params);
  cc.material = corneal_incision::cornea_material(scene.params);
  cc.springs = springs::build_springs(p, tr, cc.material.springs);
  cc.topology = cut::build_topology(p, tr, cc.springs);
  cut::CutMesh m{p, tr, cc.springs, cc.topology, cc.material};
  cut::reserve_for_cuts(m, std::max<uint32_t>(4096, p.slots.size() / 4));
  cc.grid = cut::build_triangle_grid(p, tr);
  scene.world.name_component<CorneaCutting>("cutting");
  scene.world.add(*cornea, std::move(cc));
  return true;
}

SystemDesc cornea_cut_system(Scene& scene) {
  const Entity cornea = *scene.body(BodyPart::Cornea);
  return {.name = "cornea_cut",
          .phase = Phase::Topology,
          .reads = {"tools.pose"},
          .writes = {"cornea.particles", "cornea.triangles", "cornea.cutting"},
          .run = [&scene, cornea](const FrameContext&) {
            CorneaCutting& cc = scene.world.at<CorneaCutting>(cornea);
            ++cc.frames;
            const ToolState& pose = scene.world.at<ToolState>(cc.keratome);
            const incision::KeratomeBlade blade = incision::blade_from_tool_pose(pose, cc.shape);
            const auto t0 = std::chrono::steady_clock::now();
            const incision::WoundFrame now = incision::update_wound(cc.tracker, blade, cc.spheres);
            const Vec3 d = incision::blade_frame(blade).d;
            const double along = cc.have_last_tip ? (blade.tip - cc.last_tip).dot(d) : 0.0;
            const bool withdrawing = cc.cutting && along < -kWithdrawMm;
            if (!cc.cutting || along > 0) cc.last_tip = blade.tip;  // the furthest while cutting
            cc.have_last_tip = true;
            if (cc.done) return;
            cut::CutMesh m{scene.world.at<Particles>(cornea), scene.world.at<Triangles>(cornea),
                           cc.springs, cc.topology, cc.material};
            cc.log.clear();
            // Off the cornea only once the tip is clear of its anterior surface by the same
            // margin: a tremor lifts a blade that has just touched it by less.
            const double outside_mm =
                (blade.tip - Vec3(0.0, 0.0, cc.spheres.anterior_centre_z)).norm() -
                cc.spheres.anterior_radius_mm;
            const bool clear = !now.outer.touches && outside_mm > kWithdrawMm;
            if (cc.cutting && (withdrawing || clear)) {
              end_paths(m, cc);
            } else {
              // The puncture's start triangle from the grid, so the first contact scans nothing.
              for (auto [cutter, section] :
                   {std::pair{&cc.outer, &now.outer}, std::pair{&cc.inner, &now.inner}}) {
                if (!cutter->started && section->has_puncture)
                  cutter->start_triangle = cut::nearest_binned_triangle(
                      cc.grid, m.particles, m.triangles, section->puncture);
              }
              bool made = corneal_incision::cut_surface(m, cc.outer, now.outer, cc.cut, cc.log,
                                                        cc.segments);
              made = corneal_incision::cut_surface(m, cc.inner, now.inner, cc.cut, cc.log,
                                                   cc.segments) ||
                     made;
              cc.cutting = cc.outer.started;
              cc.cutting_frames += made;
            }
            // The cornea has no spring graph to patch (its particles are anchored): drop the
            // spring changes the edits listed.
            cc.topology.added_springs.clear(), cc.topology.removed_springs.clear();
            const double ms =
                std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0)
                    .count();
            cc.edit_ms_total += ms;
            cc.edit_ms_max = std::max(cc.edit_ms_max, ms);
          }};
}

bool measure_scene_incision(Scene& scene, MeshIncision& out) {
  CorneaCutting* cc = cutting_of(scene);
  if (!cc) return false;
  out = {};
  out.wound = cc->tracker.wound;
  out.complete = cc->tracker.wound.penetrated;
  const cut::CutMesh m = mesh_of(scene, *cc);
  const auto tips = [&](const corneal_incision::SurfaceCutter& s, int k) {
    return cc->done ? s.tips[k] : corneal_incision::live_tip(m, s.side[k].path);
  };
  using corneal_incision::Surface;
  const corneal_incision::SurfaceCut outer = corneal_incision::measure_surface_cut(
      m, cc->spheres, Surface::Anterior, tips(cc->outer, 0), tips(cc->outer, 1),
      corneal_incision::tool_polyline(cc->outer));
  const corneal_incision::SurfaceCut inner = corneal_incision::measure_surface_cut(
      m, cc->spheres, Surface::Posterior, tips(cc->inner, 0), tips(cc->inner, 1),
      corneal_incision::tool_polyline(cc->inner));
  out.outer_cut = outer.exists;
  out.inner_cut = inner.exists;
  out.outer_middle = outer.middle;
  out.inner_middle = inner.middle;
  if (outer.exists) {
    const Vec3& c = outer.middle;
    out.width_mm = outer.chord_mm;
    out.clock_hour = incision::clock_hour_of(c);
    out.limbus_distance_mm = cc->spheres.limbus_radius_mm - std::hypot(c.x(), c.y());
  }
  if (outer.exists && inner.exists) {
    const Vec3 d = inner.middle - outer.middle;
    out.tunnel_length_mm = d.norm();
    if (out.tunnel_length_mm > 0.0) {
      const Vec3 u = d / out.tunnel_length_mm;
      const Vec3 n = (outer.middle - Vec3(0.0, 0.0, cc->spheres.anterior_centre_z)).normalized();
      out.entry_angle_deg = std::asin(std::clamp(-u.dot(n), -1.0, 1.0)) * kRadToDeg;
      out.iris_plane_angle_deg = std::asin(std::clamp(-u.z(), -1.0, 1.0)) * kRadToDeg;
    }
  }
  return true;
}

void incision_metrics(Scene& scene, DrillReport& out) {
  MeshIncision w;
  if (!measure_scene_incision(scene, w)) {
    out.metrics["incision.complete"] = 0;
    return;
  }
  out.metrics["incision.complete"] = w.complete ? 1 : 0;
  out.metrics["incision.cut_segments"] = cutting_of(scene)->segments;  // the blade cut: attempted
  if (w.outer_cut) {
    out.metrics["incision.width_mm"] = w.width_mm;
    out.metrics["incision.clock_hour"] = w.clock_hour;
    out.metrics["incision.limbus_distance_mm"] = w.limbus_distance_mm;
  }
  if (w.outer_cut && w.inner_cut) {
    out.metrics["incision.entry_angle_deg"] = w.entry_angle_deg;
    out.metrics["incision.iris_plane_angle_deg"] = w.iris_plane_angle_deg;
    out.metrics["incision.tunnel_length_mm"] = w.tunnel_length_mm;
  }
  CorneaCutting& cc = *cutting_of(scene);
  const cut::CutMesh m = mesh_of(scene, cc);
  out.series["incision"] = {
      {"outer_lips_mm", lip_series(m, cc.spheres, corneal_incision::Surface::Anterior)},
      {"inner_lips_mm", lip_series(m, cc.spheres, corneal_incision::Surface::Posterior)},
      {"limbus_radius_mm", cc.spheres.limbus_radius_mm}};
}

}  // namespace phaco
