#include "procedures/scene/capsule_cutting.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <stdexcept>
#include <string>

#include "components/particles.hpp"
#include "components/tool.hpp"
#include "components/triangles.hpp"
#include "engine/core/error.hpp"
#include "procedures/rhexis/opening.hpp"
#include "procedures/scene/capsule_physics.hpp"
#include "procedures/scene/scene.hpp"
#include "systems/cut/spring_order.hpp"
#include "systems/springs/springs.hpp"
#include "systems/topology_check/topology_check.hpp"

namespace phaco {

namespace {

// The width of the cystotome's bent bevel that slides in its own slit (progressive_cut.hpp,
// CutSettings::slit_mm): about a quarter of a 27-gauge needle's 0.41 mm. Its puncture is a little
// smaller than that; the tear's closing on the radial cut is sensitive to where the cut starts
// (0.1 mm here made the level-1 expert's tear miss it; 0.08 keeps levels 0-8 closing).
constexpr double kCystotomeSlitMm = 0.1, kCystotomePunctureMm = 0.08;

double elapsed_ms(std::chrono::steady_clock::time_point since) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - since)
      .count();
}

// Calls f(spring, neighbour, extension, unit vector to the neighbour) for each spring of the
// particle the forceps hold (once per neighbour), the held particle taken at `x` (systems/grasp
// puts it at the forceps' tip in this frame's dynamics).
template <class F>
void for_each_held_spring(const cut::CutMesh& m, uint32_t held, const Vec3& x, F&& f) {
  std::vector<uint32_t> fan;
  const uint32_t hint = m.topology.vertex_triangle[held];
  if (!m.triangles.slots.alive(hint)) return;
  cut::vertex_fan(m.triangles, m.topology.adjacency, hint, held, fan);
  std::vector<uint32_t> seen;
  for (uint32_t t : fan) {
    for (int k = 0; k < 3; ++k) {
      const uint32_t n = cut::corner(m.triangles, t, k);
      if (n == held || std::find(seen.begin(), seen.end(), n) != seen.end()) continue;
      seen.push_back(n);
      const auto it = m.topology.spring_of_edge.find(cut::edge_key(held, n));
      if (it == m.topology.spring_of_edge.end()) continue;
      const Vec3 d = cut::particle_position(m.particles, n) - x;
      const double len = d.norm();
      if (len <= 0) continue;
      f(it->second, n, len - m.springs.rest_length[it->second], Vec3(d / len));
    }
  }
}

// The force the forceps exert on the flap through the particle they hold: the pull of that
// particle's springs into the membrane, reversed (the held particle is kinematic, so the tool
// balances it).
Vec3 flap_force(const cut::CutMesh& m, uint32_t held, const Vec3& at) {
  Vec3 pull = Vec3::Zero();
  for_each_held_spring(m, held, at, [&](uint32_t s, uint32_t, double ext, const Vec3& d) {
    pull += m.springs.stiffness[s] * ext * d;
  });
  return -pull;
}

// The held flap folds rather than pull harder than the tear resistance (issue 17 item 5). A real
// flap is folded over the disc, so its tension reaches the tear's tip and the tear runs at F_c.
// Our membrane's springs also carry compression and the flap cannot fold, so forceps moving along
// the tear drag the held point over the disc (measured on the expert: 3.6 mm a quarter, every
// spring at the held particle stretched, the force ramping at ≈ 25 mN/mm while the tear's tip
// stays 0.2–0.3 mm from the forceps). So when the pull exceeds F_c the stretched springs at the
// held particle take the fold: their rest lengths grow until the pull is F_c.
// The original rest lengths are kept (cc.folded) and given back when the forceps let go: the
// flap unfolds.
void fold_held_flap(cut::CutMesh& m, CapsuleCutting& cc, uint32_t held, const Vec3& at,
                    double pull_mn) {
  if (pull_mn <= cc.tear.threshold_mn) return;
  const double keep = cc.tear.threshold_mn / pull_mn;
  for_each_held_spring(m, held, at, [&](uint32_t s, uint32_t n, double ext, const Vec3&) {
    if (ext <= 0) return;
    const uint64_t key = cut::edge_key(held, n);
    if (std::none_of(cc.folded.begin(), cc.folded.end(),
                     [&](const auto& f) { return f.first == key; }))
      cc.folded.emplace_back(key, m.springs.rest_length[s]);
    m.springs.rest_length[s] += static_cast<float>((1.0 - keep) * ext);
  });
}

void unfold(cut::CutMesh& m, CapsuleCutting& cc) {
  for (const auto& [key, rest] : cc.folded) {
    const auto it = m.topology.spring_of_edge.find(key);
    if (it != m.topology.spring_of_edge.end()) m.springs.rest_length[it->second] = rest;
  }
  cc.folded.clear();
}

// Brings the capsule's physics up to date after this frame's edits, touching only what they
// touched: the new springs are already in the blocks' tail (the edits append them), the removed
// ones are tombstones with stiffness 0; the graph's rows of their ends are patched; glue grows for
// the new particles (amortised, the arrays were reserved). No pass over the whole capsule.
void refresh_physics(cut::CutMesh& m, CapsuleSprings& sp, const cut::EditLog& log) {
  const uint32_t n = m.particles.slots.size();
  sp.glue.x.resize(n), sp.glue.y.resize(n), sp.glue.z.resize(n);
  for (uint32_t v : log.new_particles) {
    if (v >= n) continue;
    const Vec3 r = cut::rest_position(m.topology, v);
    sp.glue.x[v] = static_cast<float>(r.x()), sp.glue.y[v] = static_cast<float>(r.y()),
    sp.glue.z[v] = static_cast<float>(r.z());
  }
  springs::patch_spring_graph(sp.graph, sp.springs, n, m.topology.removed_springs,
                              m.topology.added_springs);
  m.topology.added_springs.clear(), m.topology.removed_springs.clear();
  ++sp.version;
}

// The tail and the tombstones are work every force pass does serially or for nothing; once they
// reach a fraction of the table the springs are compacted, sorted and re-planned, and the graph
// rebuilt — a pass over the whole capsule, so only in a frame without topology change, and rare:
// after about compact_fraction × springs changed springs, so amortised O(log S) per change.
bool compaction_due(const CapsuleSprings& sp, const CapsuleCutting& cc) {
  const uint32_t size = sp.springs.slots.size(), live = sp.springs.slots.live_count();
  const uint32_t unplanned = (size - sp.blocks.tail_begin()) + (size - live);
  return unplanned > std::max<uint32_t>(cc.compact_min_springs,
                                        static_cast<uint32_t>(cc.compact_fraction * live));
}

void compact_physics(cut::CutMesh& m, CapsuleSprings& sp) {
  cut::compact_and_sort_springs(m);
  const uint32_t n = m.particles.slots.size();
  sp.blocks = springs::plan_blocks(sp.springs, n);
  sp.graph = springs::build_spring_graph(sp.springs, n);
  ++sp.version;
}

// Debug builds check the patched structure against a fresh build after every change (O(S log S));
// release builds leave it to the tests.
void check_patched_physics(const CapsuleSprings& sp, uint32_t particle_count) {
  if constexpr (topology_check::kCheckEveryFrame) {
    const std::string problem =
        topology_check::check_spring_structure(sp.springs, sp.blocks, sp.graph, particle_count);
    if (!problem.empty()) throw std::logic_error("capsule springs after a cut: " + problem);
  }
}

// The particles this frame's edits made become sources (seeds of the active set).
void add_sources(CapsuleCutting& cc, const Particles& p, uint64_t frame) {
  for (uint32_t v : cc.log.new_particles) {
    if (!p.slots.alive(v)) continue;
    cc.sources.push_back(v);
    cc.source_frame.push_back(frame);
  }
}

// Lips older than source_frames are left to the active set's wake rules.
void prune_sources(CapsuleCutting& cc, uint64_t frame) {
  size_t keep = 0;
  for (size_t i = 0; i < cc.sources.size(); ++i) {
    if (cc.source_frame[i] + cc.source_frames <= frame) continue;
    cc.sources[keep] = cc.sources[i], cc.source_frame[keep] = cc.source_frame[i], ++keep;
  }
  cc.sources.resize(keep), cc.source_frame.resize(keep);
}

// Forceps: a temporary vertex under the tip the frame they close (seed 000 Fig. 9), removed the
// frame after systems/grasp has let go. Made on the deformed capsule; new particles are placed
// already, so their origins are not replayed, and the rest mirror gets their rest positions.
void forceps_temporary_vertices(Scene& scene, cut::CutMesh& m, CapsuleCutting& cc,
                                const CapsuleSettings& cs) {
  cc.forceps.resize(scene.tools.size());
  for (size_t k = 0; k < scene.tools.size(); ++k) {
    const ToolGrasp* g = scene.world.get<ToolGrasp>(scene.tools[k]);
    if (!g) continue;
    cut::GraspPoint& held = cc.forceps[k];
    if (held.held() && !g->capsule.holding()) {
      const cut::ReleaseReport r = cut::release(m, held, cc.log);
      cc.temporary_removed += r.removed_temporary;
      cc.temporary_kept += r.kept_temporary;
      held = {};
    }
    const ToolState& st = scene.world.at<ToolState>(scene.tools[k]);
    if (held.held() || g->capsule.holding() || g->capsule.closed || st.grip < cs.grasp.close_at)
      continue;
    const cut::CutPoint c = cut::locate_cut_point(m.particles, m.triangles, cc.topology.adjacency,
                                                  cc.contact_hint, st.pos, cc.cut.snap);
    cc.contact_hint = c.triangle;
    if (c.distance_mm > cs.grasp.radius_mm) continue;
    held = cut::grasp_at(m, c, cc.cut, cc.log);
    if (held.held() && !held.temporary) held = {};  // an existing vertex: nothing to undo
    cc.temporary_vertices += held.temporary;
  }
  for (uint32_t v : cc.log.new_particles) {
    if (cc.rest_x.size() <= v)
      cc.rest_x.resize(v + 1), cc.rest_y.resize(v + 1), cc.rest_z.resize(v + 1);
    const Vec3 r = cut::rest_position(cc.topology, v);
    cc.rest_x[v] = float(r.x()), cc.rest_y[v] = float(r.y()), cc.rest_z[v] = float(r.z());
  }
  cc.log.origins.clear();
}

// The cystotome cuts where its tip touches the capsule or is pressed through it; `rest_point` is
// that point carried to the rest shape by its barycentric weights. When the tip leaves by more
// than release_mm, the stroke ends and becomes the flap the tear continues.
void end_stroke(CapsuleCutting& cc) {
  if (cc.stroke.tip != kInvalidIndex) cc.flap = cc.stroke, cc.tear_state = {};
  cc.stroke = {}, cc.stroke_lifted = false;
}

bool cystotome_contact(Scene& scene, const cut::CutMesh& m, CapsuleCutting& cc, Vec3& rest_point) {
  bool cutting = false;
  for (Entity tool : scene.tools) {
    if (scene.world.at<Tool>(tool).kind != ToolKind::Cystotome) continue;
    const Vec3 tip = scene.world.at<ToolState>(tool).pos;
    const cut::CutPoint c = cut::locate_cut_point(m.particles, m.triangles, cc.topology.adjacency,
                                                  cc.contact_hint, tip, cc.cut.snap);
    cc.contact_hint = c.triangle;
    const uint32_t t = c.triangle;
    const Vec3 a = cut::particle_position(m.particles, m.triangles.a[t]);
    const Vec3 normal = (cut::particle_position(m.particles, m.triangles.b[t]) - a)
                            .cross(cut::particle_position(m.particles, m.triangles.c[t]) - a);
    const bool through = (tip - c.position).dot(normal) < 0.0 && c.distance_mm <= cc.penetration_mm;
    if (c.distance_mm <= cc.contact_mm || through) {
      cutting = true;
      rest_point = Vec3::Zero();
      for (int k = 0; k < 3; ++k)
        rest_point += c.bary[k] * cut::rest_position(cc.topology, cut::corner(m.triangles, t, k));
      // Back in contact away from where the stroke stopped: the blade left its hole.
      if (cc.stroke_lifted && !cc.stroke.tool_points.empty() &&
          (rest_point - cc.stroke.tool_points.back()).norm() > cc.release_mm)
        end_stroke(cc);
      cc.stroke_lifted = false;
    } else if (cc.stroke.started) {
      cc.stroke_lifted = true;
      if (c.distance_mm > cc.release_mm) end_stroke(cc);
    }
  }
  return cutting;
}

// Seed 000's f_t: the flap is a strip under tension between the forceps and the tear's tip, so the
// pull reaches the tip along the strip, with the magnitude of the held particle's springs' pull.
// Forceps holding an open tear's flap are tearing (cc.tearing, cc.flap_force_mn); `held` is the
// particle they hold and where, which folds at the tear resistance after this frame's edits
// (fold_held_flap). Closer than min_lever_mm the strip has no direction to speak of: no tear.
// `elongation` is the strip's stretch, the forceps-to-tip distance less the held particle's rest
// distance to the tip (tear_until_below relaxes the force by the tear's advance).
struct HeldFlap {
  uint32_t particle = kInvalidIndex;
  Vec3 at = Vec3::Zero();
};
bool flap_pull(Scene& scene, cut::CutMesh& m, CapsuleCutting& cc, Vec3& pull, double& elongation,
               HeldFlap& held) {
  unfold(m, cc);  // the fold is this frame's: a new pull direction meets the flap's own springs
  if (cc.flap.tip == kInvalidIndex || !m.particles.slots.alive(cc.flap.tip)) return false;
  for (Entity tool : scene.tools) {
    const ToolGrasp* g = scene.world.get<ToolGrasp>(tool);
    if (!g || !g->capsule.holding() || !m.particles.slots.alive(g->capsule.particle)) continue;
    const uint32_t h = g->capsule.particle, t = cc.flap.tip;
    const Vec3 at = scene.world.at<ToolState>(tool).pos;
    const double force = flap_force(m, h, at).norm();
    // Once the tear has closed, the held flap is the freed disc: it still folds rather than drag.
    held = {h, at};
    if (cc.tear_state.complete) return false;
    cc.tearing = true, cc.flap_force_mn = force;
    const Vec3 along = at - cut::particle_position(m.particles, t);
    if (along.norm() < cc.min_lever_mm) return false;
    // The flap's tension reaches the tip in the membrane's plane (a flap folded over the disc).
    const Vec3 normal = tear::vertex_normal(m, t);
    const Vec3 in_plane = along - along.dot(normal) * normal;
    pull =
        force * (in_plane.norm() > 1e-9 ? Vec3(in_plane.normalized()) : Vec3(along.normalized()));
    const Vec3 rest(cc.rest_x[h] - cc.rest_x[t], cc.rest_y[h] - cc.rest_y[t],
                    cc.rest_z[h] - cc.rest_z[t]);
    elongation = along.norm() - rest.norm();
    return true;
  }
  return false;
}

// The cut and the tear run in the rest shape: positions swapped with the rest mirror (vector
// swaps), the edits, the swap back, then each new particle placed on the deformed capsule by its
// origin.
void edit_in_rest_shape(cut::CutMesh& m, CapsuleCutting& cc, bool cutting, const Vec3& cut_at,
                        bool pulling, const Vec3& pull, double elongation, bool rim_tearing,
                        double time_s) {
  Particles& p = m.particles;
  const size_t replay_from = cc.log.origins.size();
  std::swap(p.x, cc.rest_x), std::swap(p.y, cc.rest_y), std::swap(p.z, cc.rest_z);
  if (cutting) {
    // The blade slides in its own slit; the tear (below) turns off the flap's end freely.
    cut::CutSettings blade = cc.cut;
    blade.slit_mm = kCystotomeSlitMm, blade.puncture_mm = kCystotomePunctureMm;
    cc.cut_segments += cut::cut_towards(m, cc.stroke, cut_at, blade, cc.log).made;
  }
  if (pulling) {
    const tear::TearRunReport run = tear::tear_until_below(m, cc.flap, cc.tear_state, pull,
                                                           elongation, cc.tear, cc.cut, cc.log);
    cc.tear_steps_last_frame = run.steps;
    cc.max_tear_steps_per_frame = std::max<uint64_t>(cc.max_tear_steps_per_frame, run.steps);
  }
  if (rim_tearing) run_rim_tears(m, cc, time_s);
  std::swap(p.x, cc.rest_x), std::swap(p.y, cc.rest_y), std::swap(p.z, cc.rest_z);
  const uint32_t n = p.slots.size();
  p.x.resize(n), p.y.resize(n), p.z.resize(n);
  for (size_t i = replay_from; i < cc.log.origins.size(); ++i) {
    const cut::ParticleOrigin& o = cc.log.origins[i];
    double x = 0, y = 0, z = 0;
    for (int k = 0; k < 3; ++k) {
      if (o.from[k] == kInvalidIndex) continue;
      x += o.weight[k] * p.x[o.from[k]], y += o.weight[k] * p.y[o.from[k]],
          z += o.weight[k] * p.z[o.from[k]];
    }
    p.x[o.particle] = static_cast<float>(x), p.y[o.particle] = static_cast<float>(y),
    p.z[o.particle] = static_cast<float>(z);
  }
}

}  // namespace

bool add_capsule_cutting(Scene& scene) {
  if (method_choice(scene, "capsule.cutting", "on") == "off") return false;
  const std::string rule = method_choice(scene, "capsule.tear_rule", "flap_force");

  const Entity capsule = *scene.body(BodyPart::Capsule);
  Particles& p = scene.world.at<Particles>(capsule);
  Triangles& tr = scene.world.at<Triangles>(capsule);
  CapsuleSprings& sp = scene.world.at<CapsuleSprings>(capsule);
  const CapsuleSettings& cs = scene.world.at<CapsuleSettings>(capsule);
  CapsuleCutting cc;
  cc.release_mm = scene.params.get("tools.cystotome_tip_mm");
  cc.material.springs = cs.material;
  cc.material.areal_density_kg_mm2 =
      scene.params.get("capsule.density_kg_m3") * 1e-9 * scene.params.get("capsule.thickness_mm");
  cc.topology = cut::build_topology(p, tr, sp.springs);
  cc.tear.rule =
      rule == "flap_force" ? tear::TearRule::FlapForce : tear::TearRule::MostStressedSpring;
  cc.tear.threshold_mn = tear::tear_resistance_mn(scene.params.get("capsule.tear_energy_j_m2"),
                                                  scene.params.get("capsule.thickness_mm"));
  // σ_u·h: what a ligament to the tear's own start holds per mm of width (systems/tear); kPa =
  // mN/mm².
  cc.tear.ligament_strength_mn_per_mm =
      scene.params.get("capsule.ultimate_stress_kpa") * scene.params.get("capsule.thickness_mm");
  cc.rim = make_rim_tears(scene, cc.tear.threshold_mn);
  double edge = 0.0;
  uint32_t counted = 0;
  for (uint32_t t = 0; t < tr.slots.size(); ++t) {
    if (!tr.slots.alive(t)) continue;
    edge += (cut::particle_position(p, tr.a[t]) - cut::particle_position(p, tr.b[t])).norm();
    ++counted;
  }
  edge /= std::max<uint32_t>(counted, 1);
  cc.cut.snap.vertex_snap_mm = std::min(0.02, 0.1 * edge);
  cc.cut.snap.edge_snap_mm = std::min(0.01, 0.05 * edge);
  cc.cut.remesh = false;  // no particle may disappear under the dynamics' feet
  cc.rest_x = p.x, cc.rest_y = p.y, cc.rest_z = p.z;
  cut::CutMesh m{p, tr, sp.springs, cc.topology, cc.material};
  const uint32_t extra = std::max<uint32_t>(4096, p.slots.size() / 4);
  cut::reserve_for_cuts(m, extra);
  for (auto* v : {&cc.rest_x, &cc.rest_y, &cc.rest_z, &sp.glue.x, &sp.glue.y, &sp.glue.z})
    v->reserve(p.slots.size() + extra);
  CapsuleSolver& solver = scene.world.at<CapsuleSolver>(capsule);
  for (auto* v : {&solver.forces.fx, &solver.forces.fy, &solver.forces.fz})
    v->reserve(p.slots.size() + extra);
  scene.world.name_component<CapsuleCutting>("cutting");
  scene.world.add(capsule, std::move(cc));
  return true;
}

SystemDesc capsule_cut_system(Scene& scene) {
  const Entity capsule = *scene.body(BodyPart::Capsule);
  return {
      .name = "capsule_cut",
      .phase = Phase::Topology,
      .reads = {"tools.pose", "tools.grasp", "capsule.settings"},
      .writes = {"capsule.particles", "capsule.triangles", "capsule.springs", "capsule.cutting"},
      .run = [&scene, capsule](const FrameContext& ctx) {
        Particles& p = scene.world.at<Particles>(capsule);
        Triangles& tr = scene.world.at<Triangles>(capsule);
        CapsuleSprings& sp = scene.world.at<CapsuleSprings>(capsule);
        const CapsuleSettings& cs = scene.world.at<CapsuleSettings>(capsule);
        CapsuleCutting& cc = scene.world.at<CapsuleCutting>(capsule);
        ++cc.frames;
        prune_sources(cc, ctx.frame);
        cut::CutMesh m{p, tr, sp.springs, cc.topology, cc.material};
        const auto t0 = std::chrono::steady_clock::now();
        cc.log.clear();
        forceps_temporary_vertices(scene, m, cc,
                                   cs);  // on the deformed capsule, where the forceps are
        Vec3 cut_at = Vec3::Zero(), pull = Vec3::Zero();
        double elongation = 0.0;
        cc.tearing = false, cc.flap_force_mn = 0.0, cc.tear_steps_last_frame = 0;
        cc.held_pull_mn = 0.0;
        HeldFlap held;
        const bool cutting = cystotome_contact(scene, m, cc, cut_at);
        const bool pulling = !cutting && flap_pull(scene, m, cc, pull, elongation, held);
        // A probe or chopper pressing the rhexis rim (rim_tear.hpp), measured where it lies.
        const bool rim_tearing = press_rim(scene, m, cc, ctx.time_s + ctx.dt_s);
        if (cutting || pulling || rim_tearing)
          edit_in_rest_shape(m, cc, cutting, cut_at, pulling, pull, elongation, rim_tearing,
                             ctx.time_s + ctx.dt_s);
        // The fold comes after the edits: a tear step through the held particle's fan gives it
        // new springs at their own rest lengths, and folding before would leave those unfolded
        // (measured: the dynamics then started from 15–31 mN at the tear's first regrasp in every
        // capsulorhexis script, and the forceps felt up to 1.48·F_c a frame later).
        if (held.particle != kInvalidIndex && m.particles.slots.alive(held.particle)) {
          fold_held_flap(m, cc, held.particle, held.at,
                         flap_force(m, held.particle, held.at).norm());
          cc.held_pull_mn = flap_force(m, held.particle, held.at).norm();
        }
        const double edit_ms = elapsed_ms(t0);
        cc.edit_ms_total += edit_ms;
        cc.edit_ms_max = std::max(cc.edit_ms_max, edit_ms);
        const bool changed = !cc.log.touched_triangles.empty() || !cc.log.new_particles.empty() ||
                             cc.log.opened_edges != 0 || !cc.topology.added_springs.empty() ||
                             !cc.topology.removed_springs.empty();
        if (!changed) {
          // A frame without topology change: the one place for the rare whole-table re-plan.
          if (compaction_due(sp, cc)) {
            const auto t2 = std::chrono::steady_clock::now();
            compact_physics(m, sp);
            ++cc.compactions;
            cc.compaction_ms_total += elapsed_ms(t2);
            check_patched_physics(sp, p.slots.size());
          }
          return;
        }
        cc.refresh_springs_total +=
            cc.topology.added_springs.size() + cc.topology.removed_springs.size();
        const auto t1 = std::chrono::steady_clock::now();
        add_sources(cc, p, ctx.frame);
        refresh_physics(m, sp, cc.log);
        const double refresh_ms = elapsed_ms(t1);
        cc.refresh_ms_total += refresh_ms;
        cc.refresh_ms_max = std::max(cc.refresh_ms_max, refresh_ms);
        ++cc.topology_changes;
        check_patched_physics(sp, p.slots.size());
      }};
}

nlohmann::json capsule_cutting_summary(Scene& scene) {
  const auto capsule = scene.body(BodyPart::Capsule);
  if (!capsule) return nullptr;
  CapsuleCutting* cc = scene.world.get<CapsuleCutting>(*capsule);
  if (!cc) return nullptr;
  CapsuleSprings& sp = scene.world.at<CapsuleSprings>(*capsule);
  const cut::CutMesh m{scene.world.at<Particles>(*capsule), scene.world.at<Triangles>(*capsule),
                       sp.springs, cc->topology, cc->material};
  const rhexis::Opening o = rhexis::measure_opening(m);
  const tear::TearState& ts = cc->tear_state;
  nlohmann::json j = {
      {"cut_segments", cc->cut_segments},
      {"topology_changes", cc->topology_changes},
      {"tear_rule", std::string(tear::to_string(cc->tear.rule))},
      {"tear_steps", ts.steps},
      {"tear_advances", ts.advances},
      {"tear_resistance_mN", cc->tear.threshold_mn},
      {"max_tear_steps_per_frame", cc->max_tear_steps_per_frame},
      {"tear_complete", ts.complete},
      {"runout_warnings", ts.count(tear::TearEvent::RunoutWarning)},
      {"radial_tearouts", ts.count(tear::TearEvent::RadialTearout)},
      {"max_tear_radius_mm", ts.max_radius_mm},
      {"edit_ms_mean_per_frame", cc->frames ? cc->edit_ms_total / double(cc->frames) : 0.0},
      {"edit_ms_max", cc->edit_ms_max},
      {"physics_refresh_ms_mean",
       cc->topology_changes ? cc->refresh_ms_total / double(cc->topology_changes) : 0.0},
      {"physics_refresh_ms_max", cc->refresh_ms_max},
      {"physics_refresh_springs_mean",
       cc->topology_changes ? double(cc->refresh_springs_total) / double(cc->topology_changes)
                            : 0.0},
      {"compactions", cc->compactions},
      {"compaction_ms_total", cc->compaction_ms_total},
      {"temporary_grasp_vertices", cc->temporary_vertices},
      {"temporary_grasp_vertices_removed", cc->temporary_removed},
      {"temporary_grasp_vertices_kept", cc->temporary_kept},
      {"opening_complete", o.complete}};
  nlohmann::json events = nlohmann::json::array();
  for (const tear::TearEvent& e : ts.events)
    events.push_back({{"kind", std::string(tear::to_string(e.kind))},
                      {"tear_step", e.step},
                      {"radius_mm", e.radius_mm},
                      {"outward_angle_deg", e.outward_angle_deg}});
  j["tear_events"] = events;
  if (o.complete) {
    j["opening_diameter_mm"] = o.diameter_mm;
    j["opening_circularity"] = o.circularity;
    j["opening_centering_mm"] = o.centering_mm;
  }
  return j;
}

}  // namespace phaco
