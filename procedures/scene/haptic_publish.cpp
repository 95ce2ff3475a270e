#include "procedures/scene/haptic_publish.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "components/body.hpp"
#include "components/particles.hpp"
#include "components/tool.hpp"
#include "components/triangles.hpp"
#include "engine/core/clock.hpp"
#include "procedures/scene/capsule_cutting.hpp"
#include "procedures/scene/capsule_physics.hpp"
#include "procedures/scene/haptic_lens_contacts.hpp"
#include "procedures/scene/scene.hpp"
#include "procedures/scene/tool_ports.hpp"

namespace phaco {
namespace {

// Clears a tool's model to "nothing near": the arrays keep their old contents, the counts say
// how much of them is meaningful.
void clear_tool(HapticTool& t) {
  t.present = false;
  t.node_count = 0;
  t.spring_count = 0;
  t.triangle_count = 0;
  t.grasped_node = kHapticNoNode;
  t.grasp_limit_mn = 0;
  t.lens_present = false;
  t.damping_mn_s_per_mm = 0;
  t.sphere_count = 0;
  t.cut_force_mn = 0;
  t.held = {};
  t.port_present = false;
}

std::array<float, 3> floats(const Vec3& v) {
  return {static_cast<float>(v.x()), static_cast<float>(v.y()), static_cast<float>(v.z())};
}

// Every particle once, for a capsule integrated whole (no active set: no locality to keep).
uint32_t nearest_by_scan(const Particles& p, uint32_t n, const Vec3& tip, double radius_mm) {
  double best = radius_mm * radius_mm;
  uint32_t best_i = kInvalidIndex;
  for (uint32_t i = 0; i < n; ++i) {
    if (!p.slots.alive(i)) continue;
    const double dx = p.x[i] - tip.x(), dy = p.y[i] - tip.y(), dz = p.z[i] - tip.z();
    const double d2 = dx * dx + dy * dy + dz * dz;
    if (d2 < best) best = d2, best_i = i;
  }
  return best_i;
}

// The k-hop ball around `seed` over the spring graph, free, and the ring outside it, anchored
// (seed 003 §III.D). Fills scratch.nodes (local → particle) and scratch.local (particle → local).
// Returns how many of the nodes are free (the first ones).
uint32_t gather_ball(const SpringGraph& graph, const Particles& p, uint32_t seed, uint32_t hops,
                     HapticPublishScratch& s) {
  s.nodes.clear();
  s.layer.assign(1, seed);
  s.local[seed] = 0;
  s.nodes.push_back(seed);
  uint32_t free_count = 1;
  for (uint32_t h = 0; h <= hops && !s.layer.empty(); ++h) {
    // The next layer: neighbours of this one not yet local.
    s.next.clear();
    for (uint32_t v : s.layer) {
      for (uint32_t k = graph.begin(v); k < graph.end(v); ++k) {
        const uint32_t w = graph.neighbour[k];
        if (w >= p.slots.size() || !p.slots.alive(w) || s.local[w] != kHapticNoNode) continue;
        s.local[w] = 0;  // marked; numbered below
        s.next.push_back(w);
      }
    }
    std::sort(s.next.begin(), s.next.end());  // a fixed local order, whatever the graph's order
    // The next layer is the anchored ring when the ball has reached k hops, or when taking it as
    // free would leave no room for the ring after it (≈ one layer more than it).
    const bool last = h == hops || s.nodes.size() + 2 * s.next.size() + 8 > kHapticMaxNodes;
    const size_t room = kHapticMaxNodes - s.nodes.size();
    if (s.next.size() > room) {
      for (size_t i = room; i < s.next.size(); ++i) s.local[s.next[i]] = kHapticNoNode;
      s.next.resize(room);
    }
    for (uint32_t w : s.next) {
      s.local[w] = static_cast<uint16_t>(s.nodes.size());
      s.nodes.push_back(w);
    }
    if (last) break;
    free_count = static_cast<uint32_t>(s.nodes.size());
    s.layer.swap(s.next);
  }
  return free_count;
}

// Keeps the bins of the capsule's particles current (systems/point_bins): all of them once, then
// each frame the active set (the only particles the step moved, a cut's new ones among them: they
// seed the set) and any appended since. A capsule integrated whole is scanned instead.
void track_capsule_particles(const Scene& scene, Entity capsule,
                             const HapticPublishSettings& settings, HapticPublishScratch& s) {
  const Particles& p = *scene.world.get<Particles>(capsule);
  if (!scene.world.get<CapsuleSettings>(capsule)->use_active_set) return;
  if (s.bins.key_of.empty()) {
    point_bins::bin_all(s.bins, p, 0.5 * settings.contact_radius_mm);
    return;
  }
  point_bins::rebin(s.bins, p, scene.world.get<CapsuleSolver>(capsule)->active.particles);
  point_bins::bin_appended(s.bins, p);
}

// Capsule triangles with three local corners into s.near_triangles (squared distance of the
// centroid to the tip, triangle). With the cut's vertex-to-triangle index, from the fans of the
// local nodes, each triangle once (from its corner of lowest local index): a walk over the ball,
// not the mesh. Without it (capsule.cutting off), a scan of every triangle.
void gather_patch(const Particles& p, const Triangles& tris, const CapsuleCutting* cutting,
                  const Vec3& tip, HapticPublishScratch& s) {
  s.near_triangles.clear();
  const auto consider = [&](uint32_t f, uint16_t from_local) {
    const uint32_t a = tris.a[f], b = tris.b[f], c = tris.c[f];
    if (a >= s.local.size() || b >= s.local.size() || c >= s.local.size()) return;
    const uint16_t la = s.local[a], lb = s.local[b], lc = s.local[c];
    if (la == kHapticNoNode || lb == kHapticNoNode || lc == kHapticNoNode) return;
    if (from_local != kHapticNoNode && from_local != std::min({la, lb, lc})) return;
    const double cx = (p.x[a] + p.x[b] + p.x[c]) / 3.0 - tip.x();
    const double cy = (p.y[a] + p.y[b] + p.y[c]) / 3.0 - tip.y();
    const double cz = (p.z[a] + p.z[b] + p.z[c]) / 3.0 - tip.z();
    s.near_triangles.emplace_back(static_cast<float>(cx * cx + cy * cy + cz * cz), f);
  };
  const cut::MembraneTopology* topo = cutting ? &cutting->topology : nullptr;
  if (!topo) {
    for (uint32_t f = 0; f < tris.slots.size(); ++f)
      if (tris.slots.alive(f)) consider(f, kHapticNoNode);
    return;
  }
  for (size_t l = 0; l < s.nodes.size(); ++l) {
    const uint32_t v = s.nodes[l];
    if (v >= topo->vertex_triangle.size()) continue;
    const uint32_t hint = topo->vertex_triangle[v];
    if (hint >= tris.slots.size() || !tris.slots.alive(hint)) continue;
    cut::vertex_fan(tris, topo->adjacency, hint, v, s.fan);
    for (uint32_t f : s.fan) consider(f, static_cast<uint16_t>(l));
  }
}

void fill_capsule(const Scene& scene, Entity capsule, const HapticPublishSettings& settings,
                  HapticPublishScratch& s, const Vec3& tip, uint32_t grasped, HapticTool& t) {
  const Particles& p = *scene.world.get<Particles>(capsule);
  const CapsuleSprings& cp = *scene.world.get<CapsuleSprings>(capsule);
  const Triangles& tris = *scene.world.get<Triangles>(capsule);
  const SpringGraph& graph = cp.graph;
  const uint32_t n = std::min(p.slots.size(), graph.particle_count());
  uint32_t seed = grasped;
  if (seed == kInvalidIndex || seed >= n)
    seed = scene.world.get<CapsuleSettings>(capsule)->use_active_set
               ? point_bins::nearest(s.bins, p, tip, settings.contact_radius_mm)
               : nearest_by_scan(p, n, tip, settings.contact_radius_mm);
  if (seed == kInvalidIndex || seed >= n) return;

  if (s.local.size() < p.slots.size()) s.local.resize(p.slots.size(), kHapticNoNode);
  const uint32_t free_count = gather_ball(graph, p, seed, settings.active_hops, s);

  t.node_count = static_cast<uint32_t>(s.nodes.size());
  double mass_sum = 0;
  uint32_t mass_n = 0;
  for (uint32_t l = 0; l < t.node_count; ++l) {
    const uint32_t i = s.nodes[l];
    t.x[l] = p.x[i], t.y[l] = p.y[i], t.z[l] = p.z[i];
    t.vx[l] = p.vx[i], t.vy[l] = p.vy[i], t.vz[l] = p.vz[i];
    t.mass[l] = p.inv_mass[i] > 0 ? 1.0f / p.inv_mass[i] : 0.0f;
    const bool free = l < free_count && p.kind[i] == ParticleKind::Free;
    t.kind[l] = i == grasped ? HapticNodeKind::Grasped
                : free       ? HapticNodeKind::Free
                             : HapticNodeKind::Anchored;
    if (t.mass[l] > 0) mass_sum += t.mass[l], ++mass_n;
  }
  if (grasped != kInvalidIndex && grasped < s.local.size() && s.local[grasped] != kHapticNoNode) {
    t.grasped_node = s.local[grasped];
  }

  // Springs between local nodes with at least one free end, each once (from its lower local end).
  for (uint32_t l = 0; l < t.node_count && t.spring_count < kHapticMaxSprings; ++l) {
    const uint32_t v = s.nodes[l];
    for (uint32_t k = graph.begin(v); k < graph.end(v); ++k) {
      const uint32_t w = graph.neighbour[k];
      const uint16_t lw = s.local[w];
      if (lw == kHapticNoNode || lw <= l) continue;
      if (t.kind[l] == HapticNodeKind::Anchored && t.kind[lw] == HapticNodeKind::Anchored) continue;
      if (t.spring_count == kHapticMaxSprings) break;
      const uint32_t sp = graph.spring[k];
      t.spring_i[t.spring_count] = static_cast<uint16_t>(l);
      t.spring_j[t.spring_count] = lw;
      t.rest_mm[t.spring_count] = cp.springs.rest_length[sp];
      t.k_mn_per_mm[t.spring_count] = cp.springs.stiffness[sp];
      ++t.spring_count;
    }
  }
  // Seed 003 §E.2–3: −(k_d + k_v)·v per node; the scene's damping and viscosity are per unit mass.
  const double mean_mass = mass_n ? mass_sum / mass_n : 0.0;
  t.damping_mn_s_per_mm =
      static_cast<float>(mean_mass * (scene.params.get("capsule_model.damping_per_s") +
                                      scene.params.get("capsule_model.viscosity_per_s")));

  // Patch: triangles with three local corners, nearest the tip first.
  gather_patch(p, tris, scene.world.get<CapsuleCutting>(capsule), tip, s);
  const size_t keep = std::min<size_t>(s.near_triangles.size(), kHapticMaxTriangles);
  std::partial_sort(s.near_triangles.begin(),
                    s.near_triangles.begin() + static_cast<std::ptrdiff_t>(keep),
                    s.near_triangles.end());
  t.triangle_count = static_cast<uint32_t>(keep);
  for (size_t k = 0; k < keep; ++k) {
    const uint32_t f = s.near_triangles[k].second;
    t.triangles[k] = {s.local[tris.a[f]], s.local[tris.b[f]], s.local[tris.c[f]]};
  }
  t.patch_stiffness_mn_per_mm = static_cast<float>(settings.patch_stiffness_mn_mm);

  for (uint32_t i : s.nodes) s.local[i] = kHapticNoNode;  // clear through the list that set them
}

}  // namespace

void fill_haptic_port(const PortsRecord& ports, size_t index, HapticTool& t) {
  t.port_present = false;
  if (index >= kMaxPortTools) return;
  const int at = ports.globe.tools[index].port;
  if (at < 0 || static_cast<size_t>(at) >= ports.ports.size()) return;
  const EyePort& port = ports.ports[static_cast<size_t>(at)];
  // The tunnel turns with the globe about its centre (systems/tool_eye), as the solve left it.
  const Eigen::Matrix3d rot = ports.globe.rotation.normalized().toRotationMatrix();
  const Vec3& gc = ports.eye.globe_centre_mm;
  t.port_present = true;
  t.port_centre_mm = floats(gc + rot * (port.centre_mm - gc));
  t.port_axis = floats(rot * port.axis);
  t.port_width_dir = floats(rot * port.width_dir);
  t.port_half_width_mm = static_cast<float>(0.5 * port.width_mm);
  t.port_tunnel_length_mm = static_cast<float>(port.tunnel_length_mm);
  t.port_stiffness_mn_per_mm = static_cast<float>(ports.stiffness.tunnel_mn_mm);
}

double haptic_tip_radius_mm(const Scene& scene, uint8_t tool_kind) {
  switch (static_cast<ToolKind>(tool_kind)) {
    case ToolKind::PhacoProbe:
      return 0.5 * scene.params.get("tools.phaco_tip_diameter_mm");
    case ToolKind::Cystotome:
      return 0.5 * scene.params.get("tools.cystotome_tip_mm");
    case ToolKind::Aspirator:
      return 0.3;  // a 0.6 mm irrigation/aspiration tip
    case ToolKind::Forceps:
    case ToolKind::Keratome:
    case ToolKind::Hook:
    case ToolKind::Chopper:
      return 0.1;  // jaw tips, blade point, hook or chopper end
  }
  return 0.1;
}

HapticPublishSettings haptic_publish_settings(const Scene& scene) {
  HapticPublishSettings s;
  s.active_hops = static_cast<uint32_t>(std::lround(scene.params.get("haptic_model.active_hops")));
  s.contact_radius_mm = scene.params.get("haptic_model.contact_radius_mm");
  s.lens_stiffness_mn_mm = scene.params.get("haptic_model.lens_stiffness_mn_mm");
  s.patch_stiffness_mn_mm = scene.params.get("haptic_model.patch_stiffness_mn_mm");
  s.lens = haptic_lens_settings(scene);
  return s;
}

void build_haptic_model(const Scene& scene, const HapticPublishSettings& settings,
                        HapticPublishScratch& scratch, HapticModel& model) {
  model.sequence = ++scratch.published;
  model.frame = scene.frame;
  model.sim_time_s = scene.time_s;
  for (HapticTool& t : model.tools) clear_tool(t);

  const auto capsule = scene.body(BodyPart::Capsule);
  const bool has_capsule_physics = capsule && scene.world.get<CapsuleSprings>(*capsule);
  const bool has_lens = scene.body(BodyPart::Lens) || scene.body(BodyPart::LensSurface);
  const bool sculptable_lens = has_sculptable_lens(scene);
  if (has_capsule_physics) track_capsule_particles(scene, *capsule, settings, scratch);
  // Each tool's tip radius, as HapticTool holds it (float), found once for the scan and the tool.
  scratch.tip_radius_mm.clear();
  for (const Entity e : scene.tools)
    scratch.tip_radius_mm.push_back(static_cast<float>(
        haptic_tip_radius_mm(scene, static_cast<uint8_t>(scene.world.get<Tool>(e)->kind))));
  // A fragment lens's cells near every tip, in one read of the centres.
  if (sculptable_lens)
    scan_lens_cells(scene, scene.tools, scratch.tip_radius_mm, settings.lens, scratch.lens);
  const PortsRecord* ports = ports_record(scene);
  for (size_t index = 0; index < scene.tools.size(); ++index) {
    const Entity e = scene.tools[index];
    const Tool& tool = *scene.world.get<Tool>(e);
    HapticTool& t = model.tools[static_cast<size_t>(tool.hand) % kHapticTools];
    const ToolState& pose = *scene.world.get<ToolState>(e);
    t.present = true;
    t.tool_kind = static_cast<uint8_t>(tool.kind);
    t.hand = static_cast<uint8_t>(tool.hand);
    t.tip_radius_mm = static_cast<float>(scratch.tip_radius_mm[index]);
    t.tip_mm = {static_cast<float>(pose.pos.x()), static_cast<float>(pose.pos.y()),
                static_cast<float>(pose.pos.z())};

    if (has_capsule_physics) {
      const ToolGrasp* g = scene.world.get<ToolGrasp>(e);
      const uint32_t grasped = g && g->capsule.holding() ? g->capsule.particle : kInvalidIndex;
      fill_capsule(scene, *capsule, settings, scratch, pose.pos, grasped, t);
      // A held flap (or the disc it freed) folds at the tear resistance: the device feels no more.
      const CapsuleCutting* cc = scene.world.get<CapsuleCutting>(*capsule);
      if (grasped != kInvalidIndex && cc && cc->flap.tip != kInvalidIndex)
        t.grasp_limit_mn = static_cast<float>(cc->tear.threshold_mn);
    }
    // A lens the tools sculpt or break is felt as it is now, spheres of its material near the tip
    // (issue 19 item 5); the analytic lens of seed 003 §E.5 only where it keeps its shape.
    if (sculptable_lens) {
      fill_lens_contacts(scene, e, settings.lens, scratch.lens, t);
    } else if (has_lens) {
      t.lens_present = true;
      t.lens_centre_mm = {0.0f, 0.0f, 0.0f};
      t.lens_equator_radius_mm =
          static_cast<float>(0.5 * scene.params.get("lens.equatorial_diameter_mm"));
      t.lens_anterior_mm = static_cast<float>(scene.params.get("lens.anterior_half_thickness_mm"));
      t.lens_posterior_mm =
          static_cast<float>(scene.params.get("lens.posterior_half_thickness_mm"));
      t.lens_stiffness_mn_per_mm = static_cast<float>(settings.lens_stiffness_mn_mm);
    }
    if (ports) fill_haptic_port(*ports, index, t);
  }
  model.published_ns = now_ns();
}

SystemDesc haptic_publish_system(Scene& scene) {
  auto settings = haptic_publish_settings(scene);
  auto scratch = std::make_shared<HapticPublishScratch>();
  return {.name = "publish_haptics",
          .phase = Phase::Publish,
          .reads = {"tools.pose", "tools.grasp", "tools.held", "tools.ports", "capsule.particles",
                    "capsule.springs", "capsule.solver", "capsule.settings", "capsule.triangles",
                    "capsule.cutting", "lens.sculpting", "lens.tets", "lens.cells"},
          .writes = {"haptics.model"},
          .run = [&scene, settings, scratch](const FrameContext&) {
            HapticModel& slot = scene.haptics->model_slot();
            build_haptic_model(scene, settings, *scratch, slot);
            scene.haptics->publish_model();
          }};
}

}  // namespace phaco
