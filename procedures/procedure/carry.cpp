#include "procedures/procedure/carry.hpp"

#include <cmath>

#include "components/body.hpp"
#include "components/particles.hpp"
#include "components/tets.hpp"
#include "components/triangles.hpp"
#include "procedures/rhexis/opening.hpp"
#include "procedures/scene/capsule_cutting.hpp"
#include "procedures/scene/capsule_physics.hpp"
#include "procedures/scene/cornea_cutting.hpp"
#include "procedures/scene/scene.hpp"
#include "systems/incision/keratome.hpp"

namespace phaco {

namespace {

// The live triangles (those `keep` marks, all when empty) and the particles they use, compacted.
CarriedSurface compact_surface(const Particles& p, const Triangles& t,
                               const std::vector<uint8_t>& keep) {
  CarriedSurface s;
  std::vector<uint32_t> index(p.x.size(), kInvalidIndex);
  const auto use = [&](uint32_t v) {
    if (index[v] == kInvalidIndex) {
      index[v] = static_cast<uint32_t>(s.vertices.size());
      s.vertices.emplace_back(p.x[v], p.y[v], p.z[v]);
      s.kind.push_back(p.kind[v]);
      s.inv_mass.push_back(p.inv_mass[v]);
    }
    return index[v];
  };
  for (uint32_t k = 0; k < t.slots.size(); ++k) {
    if (!t.slots.alive(k) || (!keep.empty() && !keep[k])) continue;
    s.triangles.push_back({use(t.a[k]), use(t.b[k]), use(t.c[k])});
  }
  return s;
}

// The main port along the tunnel the keratome cut: from the outer cut's middle to the inner's.
EyePort port_of(const MeshIncision& w) {
  EyePort port;
  port.name = "main";
  port.centre_mm = 0.5 * (w.outer_middle + w.inner_middle);
  port.axis = (w.inner_middle - w.outer_middle).normalized();
  const Vec3 radial(port.centre_mm.x(), port.centre_mm.y(), 0.0);
  port.width_dir = Vec3::UnitZ().cross(radial).normalized();  // along the limbus, ⟂ the axis
  port.width_dir = (port.width_dir - port.width_dir.dot(port.axis) * port.axis).normalized();
  port.width_mm = w.width_mm;
  port.tunnel_length_mm = w.tunnel_length_mm;
  port.clock_hour = w.clock_hour;
  return port;
}

void carry_incision(Scene& scene, CarriedState& state) {
  MeshIncision w;
  if (!measure_scene_incision(scene, w) || !w.complete || !w.outer_cut || !w.inner_cut ||
      !(w.tunnel_length_mm > 0.0))
    return;
  state.main_port = port_of(w);
  const Entity cornea = *scene.body(BodyPart::Cornea);
  state.cornea =
      compact_surface(scene.world.at<Particles>(cornea), scene.world.at<Triangles>(cornea), {});
}

void carry_capsule(Scene& scene, CarriedState& state) {
  const auto capsule = scene.body(BodyPart::Capsule);
  if (!capsule) return;
  CapsuleCutting* cc = scene.world.get<CapsuleCutting>(*capsule);
  // Nothing cut or torn: the capsule is as it came.
  if (!cc || (cc->cut_segments == 0 && cc->rim.tears.empty())) return;
  const Particles& p = scene.world.at<Particles>(*capsule);
  const Triangles& t = scene.world.at<Triangles>(*capsule);
  const cut::CutMesh m{const_cast<Particles&>(p), const_cast<Triangles&>(t),
                       scene.world.at<CapsuleSprings>(*capsule).springs, cc->topology,
                       cc->material};
  // Its shape as left (the next step's springs rest there: the opening does not spring back).
  state.capsule = compact_surface(p, t, rhexis::held_triangles(m));
  const rhexis::Opening o = rhexis::measure_opening(m);
  state.rhexis_radius_mm = o.complete ? 0.5 * o.diameter_mm : 0.0;
}

void carry_lens(Scene& scene, CarriedState& state) {
  const auto lens = scene.body(BodyPart::Lens);
  if (!lens || scene.scenario.drill != Drill::PhacoSculpting) return;
  const Tets& tets = scene.world.at<Tets>(*lens);
  std::vector<uint32_t> removed;
  for (uint32_t k = 0; k < tets.slots.size(); ++k)
    if (!tets.slots.alive(k)) removed.push_back(k);
  state.lens_removed = std::move(removed);
}

nlohmann::json vec(const Vec3& v) {
  return {v.x(), v.y(), v.z()};
}

}  // namespace

bool incision_entered_chamber(Scene& scene) {
  MeshIncision w;
  return measure_scene_incision(scene, w) && w.complete && w.outer_cut && w.inner_cut;
}

void carry_out(Scene& scene, CarriedState& state) {
  carry_incision(scene, state);
  carry_capsule(scene, state);
  carry_lens(scene, state);
}

nlohmann::json carried_json(const CarriedState& s) {
  nlohmann::json j = nlohmann::json::object();
  if (s.main_port) {
    const EyePort& p = *s.main_port;
    j["main_port"] = {{"clock_hour", p.clock_hour},
                      {"centre_mm", vec(p.centre_mm)},
                      {"axis", vec(p.axis)},
                      {"width_mm", p.width_mm},
                      {"tunnel_length_mm", p.tunnel_length_mm}};
  }
  if (s.cornea) j["cornea_triangles"] = s.cornea->triangles.size();
  if (s.capsule) j["capsule_triangles"] = s.capsule->triangles.size();
  if (s.rhexis_radius_mm) j["rhexis_radius_mm"] = *s.rhexis_radius_mm;
  if (s.lens_removed) j["lens_tets_removed"] = s.lens_removed->size();
  return j;
}

}  // namespace phaco
