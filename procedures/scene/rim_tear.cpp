#include "procedures/scene/rim_tear.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <string>

#include "components/particles.hpp"
#include "components/tool.hpp"
#include "components/triangles.hpp"
#include "engine/io/tool_shape.hpp"
#include "procedures/scene/capsule_cutting.hpp"
#include "procedures/scene/capsule_physics.hpp"
#include "procedures/scene/scene.hpp"
#include "systems/lens_tools/cell_dynamics.hpp"

namespace phaco {

namespace {

Vec3 at(const cut::CutMesh& m, uint32_t v) {
  return cut::particle_position(m.particles, v);
}

uint32_t third_corner(const Triangles& t, uint32_t tri, uint32_t a, uint32_t b) {
  for (int k = 0; k < 3; ++k) {
    const uint32_t c = cut::corner(t, tri, k);
    if (c != a && c != b) return c;
  }
  return a;
}

// The tool's section's reach past the rim point it pressed, along its push: r + (P − pressed)·
// outward, P the shaft's crossing of the capsule's surface; 0 when it does not cross it, or
// crosses it more than `along_mm` along the rim from that point (it has moved off the tear).
double push_on(const RimTear& t, const Vec3& tip, const Vec3& shaft, double radius_mm,
               const RimTearSettings& s, double along_mm) {
  const std::optional<Vec3> p = capsule_crossing(tip, shaft, s);
  if (!p) return 0.0;
  const Vec3 tangent = t.normal.cross(t.outward);
  if (std::abs((*p - t.pressed).dot(tangent)) > along_mm) return 0.0;
  return std::max(0.0, radius_mm + (*p - t.pressed).dot(t.outward));
}

// The tear a tool is driving, or −1.
int driven_by(const RimTears& rt, size_t tool) {
  for (size_t i = rt.tears.size(); i-- > 0;)
    if (rt.tears[i].tool == tool && rt.tears[i].driven) return static_cast<int>(i);
  return -1;
}

// The notch nearest `where` among the rim's vertices within `reach_mm` of it, or kInvalidIndex.
uint32_t notch_near(const cut::CutMesh& m, std::span<const RimEdge> rim, const Vec3& where,
                    double reach_mm, double notch_angle_deg) {
  uint32_t best = kInvalidIndex;
  double best_d = reach_mm;
  for (const RimEdge& e : rim) {
    for (const uint32_t v : {e.a, e.b}) {
      const double d = (at(m, v) - where).norm();
      if (d > best_d || (d == best_d && v >= best)) continue;
      if (membrane_angle_deg(m, v) < notch_angle_deg) continue;
      best = v, best_d = d;
    }
  }
  return best;
}

// The nick: the tear's path from the rim vertex a step into the membrane (the initial cut); a step
// the quality snap refuses (the cut waits inside a triangle) is tried longer.
bool start_path(cut::CutMesh& m, RimTear& t, const tear::TearSettings& ts,
                const cut::CutSettings& cs, cut::EditLog& log) {
  if (!m.particles.slots.alive(t.start_vertex)) return false;
  const Vec3 from = at(m, t.start_vertex);
  if (!t.path.started) {
    // Located from the vertex's own fan: a walk from afar stops at the opening's far side.
    t.path.hint_triangle = m.topology.vertex_triangle[t.start_vertex];
    cut::cut_towards(m, t.path, from, cs, log);
  }
  for (const double d : {1.0, 2.0, 4.0}) {
    if (t.path.tip != kInvalidIndex) break;
    cut::cut_towards(m, t.path, from + d * ts.max_step_mm * t.outward, cs, log);
  }
  return t.path.tip != kInvalidIndex;
}

}  // namespace

std::vector<RimEdge> rim_edges(const cut::CutMesh& m) {
  std::vector<RimEdge> out;
  const Triangles& t = m.triangles;
  const auto& neighbour = m.topology.adjacency.neighbour;
  for (uint32_t k = 0; k < t.slots.size(); ++k) {
    if (!t.slots.alive(k)) continue;
    for (int e = 0; e < 3; ++e) {
      if (neighbour[k][e] != kInvalidIndex) continue;
      const uint32_t a = cut::corner(t, k, e), b = cut::corner(t, k, (e + 1) % 3);
      if (m.particles.kind[a] == ParticleKind::Anchored ||
          m.particles.kind[b] == ParticleKind::Anchored)
        continue;  // the outer rim, held by the zonules
      const Vec3 n = tear::vertex_normal(m, a) + tear::vertex_normal(m, b);
      out.push_back({a, b, k, n.norm() > 0 ? Vec3(n.normalized()) : Vec3(Vec3::UnitZ())});
    }
  }
  return out;
}

std::optional<Vec3> capsule_crossing(const Vec3& tip, const Vec3& shaft, const RimTearSettings& s) {
  // q(x) = (x² + y²)/R² + z²/c² along tip + t·shaft: a quadratic in t; inside the lens q < 1.
  const double ia = 1.0 / (s.lens_radius_mm * s.lens_radius_mm),
               ic = 1.0 / (s.lens_anterior_mm * s.lens_anterior_mm);
  const double a =
      (shaft.x() * shaft.x() + shaft.y() * shaft.y()) * ia + shaft.z() * shaft.z() * ic;
  const double b =
      2.0 * ((tip.x() * shaft.x() + tip.y() * shaft.y()) * ia + tip.z() * shaft.z() * ic);
  const double c = (tip.x() * tip.x() + tip.y() * tip.y()) * ia + tip.z() * tip.z() * ic - 1.0;
  if (c >= 0 || a <= 0) return std::nullopt;                           // the tip is not in the lens
  const double t = (-b + std::sqrt(b * b - 4.0 * a * c)) / (2.0 * a);  // c < 0: one root > 0
  const Vec3 p = tip + t * shaft;
  if (t > s.shaft_mm || p.z() <= 0) return std::nullopt;  // out through the posterior half
  return p;
}

RimPress rim_press(const cut::CutMesh& m, std::span<const RimEdge> rim, const Vec3& tip,
                   const Vec3& shaft, double radius_mm, const RimTearSettings& s) {
  RimPress best;
  const std::optional<Vec3> crossing = capsule_crossing(tip, shaft, s);
  if (!crossing) return best;
  const Vec3& p = *crossing;
  // The rim point nearest the crossing (the rim is a polyline: an edge's line reaches past its
  // corners), and the edge's in-plane normal into the membrane.
  const auto nearest_on = [&](const RimEdge& e, Vec3& q, Vec3& w, Vec3& outward) {
    const Vec3 a = at(m, e.a), b = at(m, e.b);
    Vec3 along = b - a;
    const double length = along.norm();
    if (length <= 0) return std::numeric_limits<double>::infinity();
    along /= length;
    q = a + std::clamp((p - a).dot(along), 0.0, length) * along;
    w = p - q;
    w -= w.dot(e.normal) * e.normal;  // in the membrane's plane there
    outward = e.normal.cross(along);
    if (outward.norm() > 1e-9) outward.normalize();
    if (outward.dot(at(m, third_corner(m.triangles, e.triangle, e.a, e.b)) - a) < 0)
      outward = -outward;
    return w.norm();
  };
  double nearest = std::numeric_limits<double>::infinity();
  const RimEdge* edge = nullptr;
  Vec3 q, w, outward;
  for (const RimEdge& e : rim) {
    Vec3 qe, we, oe;
    if (const double d = nearest_on(e, qe, we, oe); d < nearest)
      nearest = d, edge = &e, q = qe, w = we, outward = oe;
  }
  if (!edge) return best;
  // Which side: where the nearest point is a corner, every edge meeting there votes with its
  // normal (a pseudo-normal: one edge's alone can point anywhere, e.g. a nick's lip at its mouth;
  // a vertex and its copies across a cut share the corner).
  Vec3 vote = outward;
  if ((q - at(m, edge->a)).norm() <= 1e-9 || (q - at(m, edge->b)).norm() <= 1e-9) {
    vote = Vec3::Zero();
    for (const RimEdge& e : rim) {
      if ((at(m, e.a) - q).norm() > 1e-9 && (at(m, e.b) - q).norm() > 1e-9) continue;
      Vec3 qe, we, oe;
      nearest_on(e, qe, we, oe);
      vote += oe;
    }
  }
  const double side = w.dot(vote) >= 0 ? 1.0 : -1.0;  // +: over the membrane
  best.crossing = true;
  best.depth_mm = radius_mm + side * nearest;
  best.at = q;
  best.outward = nearest > 1e-6 ? Vec3(side * w / nearest) : outward;  // the tool's push
  best.normal = edge->normal;
  best.vertex = (q - at(m, edge->a)).norm() <= (q - at(m, edge->b)).norm() ? edge->a : edge->b;
  return best;
}

double membrane_angle_deg(const cut::CutMesh& m, uint32_t v) {
  const uint32_t hint = m.topology.vertex_triangle[v];
  if (hint >= m.triangles.slots.size() || !m.triangles.slots.alive(hint)) return 0.0;
  std::vector<uint32_t> fan;
  cut::vertex_fan(m.triangles, m.topology.adjacency, hint, v, fan);
  const Vec3 x = at(m, v);
  double sum = 0.0;
  for (uint32_t t : fan) {
    Vec3 d[2];
    int n = 0;
    for (int k = 0; k < 3 && n < 2; ++k)
      if (const uint32_t c = cut::corner(m.triangles, t, k); c != v) d[n++] = at(m, c) - x;
    if (n == 2) sum += std::atan2(d[0].cross(d[1]).norm(), d[0].dot(d[1]));
  }
  return sum * 180.0 / std::numbers::pi;
}

RimTears make_rim_tears(const Scene& scene, double tear_resistance_mn) {
  RimTears rt;
  rt.settings.stiffness_mn_mm = scene.params.get("capsule.rim_stiffness_mn_mm");
  rt.settings.smooth_strength_mn = scene.params.get("capsule.rim_strength_mn");
  rt.settings.notched_strength_mn = tear_resistance_mn;
  rt.settings.outer_radius_mm = scene.params.get("capsule.radius_mm");
  rt.settings.lens_radius_mm = 0.5 * scene.params.get("lens.equatorial_diameter_mm");
  rt.settings.lens_anterior_mm = scene.params.get("lens.anterior_half_thickness_mm");
  for (Entity tool : scene.tools) {
    double r = 0.0;  // forceps grasp and the cystotome cuts (capsule_cutting): they do not press
    switch (scene.world.get<Tool>(tool)->kind) {
      case ToolKind::PhacoProbe:
        r = 0.5 * scene.params.get("tools.phaco_tip_diameter_mm");
        break;
      case ToolKind::Chopper:
      case ToolKind::Hook:
      case ToolKind::Aspirator:
        r = lens_tools::HookSettings{}.radius_mm;  // the lens tools' shaft cylinder
        break;
      default:
        break;
    }
    rt.tool_radius_mm.push_back(r);
  }
  rt.tool_max_force_mn.assign(scene.tools.size(), 0.0);
  return rt;
}

bool press_rim(Scene& scene, cut::CutMesh& m, CapsuleCutting& cc, double time_s) {
  RimTears& rt = cc.rim;
  const RimTearSettings& s = rt.settings;
  rt.pending.clear();
  if (std::none_of(rt.tool_radius_mm.begin(), rt.tool_radius_mm.end(),
                   [](double r) { return r > 0; }))
    return false;
  if (rt.rim_version != cc.topology_changes) {
    rt.rim = rim_edges(m);
    rt.rim_version = cc.topology_changes;
  }
  if (rt.rim.empty()) return false;  // a whole capsule: no opening to press
  rt.presses.assign(scene.tools.size(), RimPress{});
  bool pressed = false;
  for (size_t k = 0; k < scene.tools.size(); ++k) {
    const double r = rt.tool_radius_mm[k];
    if (r <= 0) continue;
    // The shaft presses the rim where its axis crosses the capsule: beside the tip for a bent
    // chopper or hook (engine/io/tool_shape.hpp), through it for the probe.
    const ShaftAxis axis = shaft_axis(scene.world.at<ToolState>(scene.tools[k]),
                                      scene.world.at<Tool>(scene.tools[k]).kind);
    const Vec3& shaft = axis.direction;
    if (const int i = driven_by(rt, k); i >= 0) {
      RimTear& t = rt.tears[static_cast<size_t>(i)];
      const double depth = push_on(t, axis.point, shaft, r, s, 4.0 * r);
      if (depth > 0) {
        t.pushed_mm = std::max(t.pushed_mm, depth);
        rt.tool_max_force_mn[k] = std::max(rt.tool_max_force_mn[k], s.stiffness_mn_mm * depth);
        pressed = true;
        if (!t.state.complete &&
            s.stiffness_mn_mm * (t.pushed_mm - t.advance_mm) >= s.notched_strength_mn)
          rt.pending.push_back(static_cast<uint32_t>(i));
        continue;
      }
      t.driven = false;  // withdrawn: its tip stays on the rim as a notch
    }
    const RimPress p = rim_press(m, rt.rim, axis.point, shaft, r, s);
    rt.presses[k] = p;
    if (!p.crossing) continue;
    rt.min_clearance_mm = std::min(rt.min_clearance_mm, -p.depth_mm);
    if (p.depth_mm <= 0) continue;
    const double force = s.stiffness_mn_mm * p.depth_mm;
    rt.tool_max_force_mn[k] = std::max(rt.tool_max_force_mn[k], force);
    pressed = true;
    const uint32_t notch = notch_near(m, rt.rim, p.at, 2.0 * r, s.notch_angle_deg);
    const bool notched = notch != kInvalidIndex;
    if (force < (notched ? s.notched_strength_mn : s.smooth_strength_mn)) continue;
    RimTear t;
    t.tool = k, t.notched = notched, t.time_s = time_s, t.start_force_mn = force;
    t.start_vertex = notched ? notch : p.vertex;
    t.origin = at(m, t.start_vertex);
    t.pressed = p.at, t.outward = p.outward, t.normal = p.normal;
    // At a notch the tool wedges it open: the tear runs on from its tip, away from the tool.
    if (Vec3 on = t.origin - p.at; notched && (on -= on.dot(p.normal) * p.normal).norm() > 1e-3)
      t.outward = on.normalized();
    t.pushed_mm = p.depth_mm;
    rt.tears.push_back(std::move(t));
    rt.events.push_back({time_s, "rim_tear", k, "force_mN", force});
    rt.pending.push_back(static_cast<uint32_t>(rt.tears.size() - 1));
  }
  for (const double f : rt.tool_max_force_mn) rt.max_force_mn = std::max(rt.max_force_mn, f);
  rt.pressing_frames += pressed;
  return !rt.pending.empty();
}

void run_rim_tears(cut::CutMesh& m, CapsuleCutting& cc, double time_s) {
  RimTears& rt = cc.rim;
  const RimTearSettings& s = rt.settings;
  tear::TearSettings ts = cc.tear;
  ts.rule = tear::TearRule::FlapForce;  // the tool's push is a force
  ts.threshold_mn = s.notched_strength_mn;
  ts.outward_bias = 0.0;
  for (const uint32_t i : rt.pending) {
    RimTear& t = rt.tears[i];
    if (t.path.tip == kInvalidIndex && !start_path(m, t, ts, cc.cut, cc.log)) continue;
    const double remaining = t.pushed_mm - t.advance_mm;
    const double force = s.stiffness_mn_mm * remaining;
    if (force >= s.notched_strength_mn && !t.state.complete) {
      const tear::TearRunReport run = tear::tear_until_below(m, t.path, t.state, force * t.outward,
                                                             remaining, ts, cc.cut, cc.log);
      t.advance_mm += run.advance_mm;
    }
    const Vec3 tip = at(m, t.path.tip);
    t.length_mm = std::max(t.length_mm, (tip - t.origin).norm());
    const double radius = std::hypot(tip.x(), tip.y());
    if (!t.to_equator && radius >= s.outer_radius_mm - s.equator_margin_mm) {
      t.to_equator = true;
      ++rt.to_equator;
      rt.events.push_back({time_s, "rim_tear_to_equator", t.tool, "radius_mm", radius});
    }
  }
}

void rim_metrics(Scene& scene, nlohmann::json& metrics) {
  const auto capsule = scene.body(BodyPart::Capsule);
  const CapsuleCutting* cc = capsule ? scene.world.get<CapsuleCutting>(*capsule) : nullptr;
  if (!cc || (cc->rim.rim.empty() && cc->rim.tears.empty())) return;
  const RimTears& rt = cc->rim;
  // The notches on the rim as it is now (a nicked or torn rim; the tips of the tears pressed).
  CapsuleSprings& sp = scene.world.at<CapsuleSprings>(*capsule);
  CapsuleCutting& mc = scene.world.at<CapsuleCutting>(*capsule);
  const cut::CutMesh m{scene.world.at<Particles>(*capsule), scene.world.at<Triangles>(*capsule),
                       sp.springs, mc.topology, mc.material};
  std::vector<uint32_t> notches;
  for (const RimEdge& e : rim_edges(m))
    for (const uint32_t v : {e.a, e.b})
      if (membrane_angle_deg(m, v) >= rt.settings.notch_angle_deg) notches.push_back(v);
  std::sort(notches.begin(), notches.end());
  metrics["rim.notches"] = std::unique(notches.begin(), notches.end()) - notches.begin();
  metrics["rim.max_force_mN"] = rt.max_force_mn;
  for (size_t k = 0; k < scene.tools.size() && k < rt.tool_max_force_mn.size(); ++k) {
    if (rt.tool_radius_mm[k] <= 0) continue;
    const Hand hand = scene.world.at<Tool>(scene.tools[k]).hand;
    metrics["rim.max_force_mN." + std::string(to_string(hand))] = rt.tool_max_force_mn[k];
  }
  if (rt.min_clearance_mm < 1e9) metrics["rim.clearance_mm.min"] = rt.min_clearance_mm;
  metrics["rim.pressing_frames"] = rt.pressing_frames;
  metrics["rim.tears"] = rt.tears.size();
  metrics["rim.tears_to_equator"] = rt.to_equator;
  double longest = 0.0;
  for (const RimTear& t : rt.tears) longest = std::max(longest, t.length_mm);
  metrics["rim.tear_length_mm.max"] = longest;
}

}  // namespace phaco
