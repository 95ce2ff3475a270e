// The haptic thread's local force model: see haptic_model.hpp and docs/haptic_model.md.
// Everything here works on the fixed arrays of HapticToolState: no allocation, no lock, no throw.
// The tick's pipeline (sides, proxy, grasp, lens, coupling, crossfade) is here; the patch contacts
// and the proxy's solve are in patch_contacts.cpp, the local nodes' step in local_nodes.cpp.
#include "systems/haptic_model/haptic_model.hpp"

#include <algorithm>
#include <cmath>

#include "systems/haptic_model/local_nodes.hpp"
#include "systems/haptic_model/patch_contacts.hpp"
#include "systems/haptic_model/proxy_planes.hpp"

namespace phaco::haptic_model {
namespace {

using detail::closest_on_triangle;
using detail::compute_normals;
using detail::finite;
using detail::gather_contacts;
using detail::integrate_nodes;
using detail::node;
using detail::Plane;
using detail::Planes;
using detail::reset_nodes;
using detail::solve_proxy;

constexpr double kHalfPi = 1.57079632679489661923;
constexpr int kArcSamples = 33;  // 32 intervals per quarter meridian

struct ArcTable {
  std::array<double, kArcSamples> c{}, s{};
};

// cos/sin of the scan angles, built once (a function-local static: after the first call, reading
// it is a plain load).
const ArcTable& arc_table() {
  static const ArcTable table = [] {
    ArcTable t;
    for (int k = 0; k < kArcSamples; ++k) {
      const double th = kHalfPi * k / (kArcSamples - 1);
      t.c[k] = std::cos(th), t.s[k] = std::sin(th);
    }
    return t;
  }();
  return table;
}

// The tool's side of each new triangle is read from where the simulation had the tool (tip_mm):
// the simulation keeps its tool outside, while the proxy carried over from the previous model may
// already be behind a triangle that moved between the two publishes.
void init_sides(HapticSlot& s, HapticScratch& sc) {
  compute_normals(s, sc);
  const Vec3 tip(s.model.tip_mm[0], s.model.tip_mm[1], s.model.tip_mm[2]);
  const uint32_t nt = std::min(s.model.triangle_count, kHapticMaxTriangles);
  for (uint32_t t = 0; t < nt; ++t) {
    const double sd = sc.tnx[t] * tip.x() + sc.tny[t] * tip.y() + sc.tnz[t] * tip.z() - sc.td[t];
    s.side[t] = sd >= 0 ? 1 : -1;
  }
}

// One tick of one model: contacts, nodes, proxy, force.
void tick_slot(HapticSlot& s, HapticScratch& sc, const Vec3& dev, const Vec3& dev_vel,
               const Vec3& shaft, const Vec3& axis_offset, const HapticSettings& st,
               uint64_t& resets) {
  const HapticTool& m = s.model;
  s.active = 0, s.penetration_mm = 0, s.lens_depth_mm = 0, s.sphere_depth_mm = 0, s.iterations = 0;
  const double dt = st.dt_s;
  if (!m.present) {
    s.proxy_velocity = (dev - s.proxy) / dt;
    s.proxy = dev, s.surface_proxy = dev, s.force = Vec3::Zero(), s.held = {};
    return;
  }
  const double r = std::max(0.0, double(m.tip_radius_mm));
  const double kc = st.coupling_stiffness_mn_per_mm;
  const double kp =
      m.patch_stiffness_mn_per_mm > 0 ? double(m.patch_stiffness_mn_per_mm) : st.rigid_ratio * kc;
  const double ks = kc * kp / (kc + kp);
  const uint32_t grasped = m.grasped_node < m.node_count ? m.grasped_node : kHapticMaxNodes;

  // 1–2. contacts seen from the device, then the local nodes.
  std::array<HapticContact, kHapticMaxContacts> contacts;
  uint32_t nc = 0;
  compute_normals(s, sc);
  gather_contacts(s, sc, dev, r, st, contacts, nc);
  if (m.node_count > 0) {
    bool ok = true;
    s.iterations = integrate_nodes(s, sc, dev, kc, ks, r, contacts, nc, st, ok);
    if (!ok) reset_nodes(s), ++resets;
    compute_normals(s, sc);
  }

  // 3. proxy.
  Vec3 p;
  Vec3 port_force = Vec3::Zero();  // while grasping: the port's own proxy's pull
  if (grasped < m.node_count) {
    p = node(s, grasped);
    s.active |= kTermGrasp;
    Planes port;
    const uint32_t n = detail::add_port_planes(m, dev, shaft, axis_offset, r, port, 0);
    if (n > 0) {
      port_force = kc * (solve_proxy(dev, dev, kc, r, port, n) - dev);
      if (port_force.squaredNorm() > 0) s.active |= kTermPort;
    }
  } else {
    Planes planes;
    uint32_t np = 0;
    nc = 0;
    gather_contacts(s, sc, dev, r, st, contacts, nc);
    const double kf = m.lens_stiffness_mn_per_mm;
    auto build = [&](const Vec3& at) {
      np = 0;
      for (uint32_t c = 0; c < nc; ++c)
        planes[np++] = {contacts[c].normal, contacts[c].point, kp * contacts[c].weight};
      if (m.lens_present && kf > 0) {
        const LensContact lc = lens_penetration(m, at, r);
        if (lc.depth_mm > -r) planes[np++] = {lc.normal, lc.nearest_mm, kf};
      }
    };
    build(dev);
    const uint32_t first_port = np;
    np = detail::add_port_planes(m, dev, shaft, axis_offset, r, planes, np);
    const uint32_t first_sphere = np;
    if (m.sphere_count > 0) {
      Planes rigid;
      double unused = 0;
      const uint32_t nq = detail::add_sphere_planes(m, s.surface_proxy, dev, r, st.rigid_ratio * kc,
                                                    rigid, 0, unused);
      s.surface_proxy = solve_proxy(dev, s.surface_proxy, kc, r, rigid, nq);
      np =
          detail::add_sphere_planes(m, s.surface_proxy, dev, r, 0.0, planes, np, s.sphere_depth_mm);
    } else {
      s.surface_proxy = dev;
    }
    p = solve_proxy(dev, s.proxy, kc, r, planes, np);
    for (uint32_t j = first_port; j < first_sphere; ++j)
      if (r - planes[j].normal.dot(p - planes[j].point) > 0) s.active |= kTermPort;
    for (uint32_t j = first_sphere; j < np; ++j) {
      const double pen = r - planes[j].normal.dot(p - planes[j].point);
      if (!(pen > 0)) continue;
      s.active |= kTermSpheres;
      if (planes[j].cap > 0 && planes[j].k * pen >= planes[j].cap * (1 - 1e-9))
        s.active |= kTermCut;
    }
    for (uint32_t c = 0; c < nc; ++c) {
      const double pen = r - contacts[c].normal.dot(p - contacts[c].point);
      if (pen > 0) s.active |= kTermContact, s.penetration_mm = std::max(s.penetration_mm, pen);
    }
    if (m.lens_present && kf > 0) {
      const LensContact lc = lens_penetration(m, p, r);
      if (lc.depth_mm > 0) s.active |= kTermLens, s.lens_depth_mm = lc.depth_mm;
    }
  }

  // 4. virtual coupling.
  s.proxy_velocity = (p - s.proxy) / dt;
  s.proxy = p;
  s.force = -kc * (dev - p) - st.coupling_damping_mn_s_per_mm * (dev_vel - s.proxy_velocity);
  // A held flap tears rather than pull harder than its tear resistance (issue 17 item 5).
  if (grasped < m.node_count && m.grasp_limit_mn > 0) {
    const double mag = s.force.norm(), limit = m.grasp_limit_mn;
    if (mag > limit) s.force *= limit / mag;
  }
  s.force += port_force;  // the flap's bound is the flap's; the tunnel pushes on the shaft
  // A held fragment hangs from the proxy (held_load.cpp); its load goes to the hand.
  if (m.held.held) {
    s.force += detail::held_load(m.held, p, s.proxy_velocity, st, s.held);
    s.active |= kTermHeld;
  } else {
    s.held = {};
  }

  // The god-object's memory: a triangle's side changes only when the proxy has gone round it —
  // clear of its plane and beside it (projection outside); over the face, the side it had holds
  // (the proxy cannot have passed through, so a face seen from behind has moved or tilted past it).
  const uint32_t nt = std::min(m.triangle_count, kHapticMaxTriangles);
  for (uint32_t t = 0; t < nt; ++t) {
    if (!sc.tvalid[t]) continue;
    const double sd = sc.tnx[t] * p.x() + sc.tny[t] * p.y() + sc.tnz[t] * p.z() - sc.td[t];
    if (std::abs(sd) <= r + st.contact_margin_mm || (sd > 0) == (s.side[t] > 0)) continue;
    const auto& tri = m.triangles[t];
    std::array<double, 3> w;
    bool inside = false;
    closest_on_triangle(p, node(s, tri[0]), node(s, tri[1]), node(s, tri[2]), w, inside);
    if (!inside) s.side[t] = sd > 0 ? 1 : -1;
  }
}

}  // namespace

LensContact lens_penetration(const HapticTool& tool, const Vec3& p, double radius_mm) {
  LensContact out;
  if (!tool.lens_present) return out.depth_mm = -1e9, out.signed_distance_mm = 1e9, out;
  const Vec3 centre(tool.lens_centre_mm[0], tool.lens_centre_mm[1], tool.lens_centre_mm[2]);
  const Vec3 rel = p - centre;
  const double rho = std::hypot(rel.x(), rel.y()), zz = rel.z();
  const double a = tool.lens_equator_radius_mm;
  const double c_half[2] = {tool.lens_anterior_mm, tool.lens_posterior_mm};
  const double own = zz >= 0 ? c_half[0] : c_half[1];
  const double f = (rho / a) * (rho / a) + (zz / own) * (zz / own);
  const bool inside = f < 1;
  // Far outside: the gap between the surface and its copy scaled by √f is ≥ (√f − 1)·min axis.
  const double bound = (std::sqrt(f) - 1) * std::min({a, c_half[0], c_half[1]});
  if (bound > radius_mm + 1.0) {
    out.signed_distance_mm = bound, out.depth_mm = radius_mm - bound;
    return out;
  }
  const ArcTable& tab = arc_table();
  double best = 1e300, best_t = 0;
  int best_h = 0;
  for (int h = 0; h < 2; ++h) {
    const double c = c_half[h], sg = h == 0 ? 1.0 : -1.0;
    int kbest = 0;
    double dbest = 1e300;
    for (int k = 0; k < kArcSamples; ++k) {
      const double er = rho - a * tab.c[k], ez = zz - sg * c * tab.s[k];
      const double d2 = er * er + ez * ez;
      if (d2 < dbest) dbest = d2, kbest = k;
    }
    // Newton on the arc parameter θ, kept within the scan cell around the best sample.
    const double h_step = kHalfPi / (kArcSamples - 1);
    const double lo = std::max(0.0, (kbest - 1) * h_step),
                 hi = std::min(kHalfPi, (kbest + 1) * h_step);
    double th = kbest * h_step;
    for (int it = 0; it < 8; ++it) {
      const double ct = std::cos(th), st = std::sin(th);
      const double qr = a * ct, qz = sg * c * st;
      const double dr = -a * st, dz = sg * c * ct;  // q'
      const double g = -((rho - qr) * dr + (zz - qz) * dz);
      const double hss = dr * dr + dz * dz - ((rho - qr) * (-qr) + (zz - qz) * (-qz));
      double next = hss > 1e-12 ? th - g / hss : th - 0.1 * h_step * (g > 0 ? 1 : -1);
      next = std::clamp(next, lo, hi);
      if (std::abs(next - th) < 1e-14) break;
      th = next;
    }
    const double er = rho - a * std::cos(th), ez = zz - sg * c * std::sin(th);
    const double refined = er * er + ez * ez;
    const double d2 = std::min(refined, dbest);
    if (d2 < best) best = d2, best_t = refined <= dbest ? th : kbest * h_step, best_h = h;
  }
  const double c = c_half[best_h], sg = best_h == 0 ? 1.0 : -1.0;
  const double qr = a * std::cos(best_t), qz = sg * c * std::sin(best_t);
  const Vec3 e = rho > 1e-12 ? Vec3(rel.x() / rho, rel.y() / rho, 0) : Vec3::UnitX();
  Vec3 n2(qr / (a * a), 0, qz / (c * c));  // outward gradient in the meridian plane
  n2.normalize();
  out.normal = n2.x() * e + Vec3(0, 0, n2.z());
  out.nearest_mm = centre + qr * e + Vec3(0, 0, qz);
  const double dist = std::sqrt(best);
  out.signed_distance_mm = inside ? -dist : dist;
  out.depth_mm = radius_mm - out.signed_distance_mm;
  return out;
}

void adopt_model(const HapticTool& model, HapticToolState& state, const HapticSettings& settings) {
  HapticSlot& cur = state.slot[state.newest];
  const uint8_t target = state.newest ^ 1;
  HapticSlot& next = state.slot[target];
  // A model replaced mid-blend: keep the share it still had as a decaying offset, so the switch
  // itself does not jump.
  if (state.blending && next.live) {
    state.offset =
        state.offset * state.offset_weight + (1.0 - state.blend_weight) * (next.force - cur.force);
    state.offset_weight = 1.0;
  }
  next.model = model;
  if (next.model.node_count > kHapticMaxNodes) next.model.node_count = kHapticMaxNodes;
  if (next.model.triangle_count > kHapticMaxTriangles)
    next.model.triangle_count = kHapticMaxTriangles;
  if (next.model.sphere_count > kHapticMaxSpheres) next.model.sphere_count = kHapticMaxSpheres;
  next.live = true;
  reset_nodes(next);
  const bool carry = cur.live && cur.model.present;
  next.proxy = carry ? cur.proxy : Vec3(model.tip_mm[0], model.tip_mm[1], model.tip_mm[2]);
  next.proxy_velocity = carry ? cur.proxy_velocity : Vec3::Zero();
  next.surface_proxy = carry ? cur.surface_proxy : next.proxy;
  next.force = cur.live ? cur.force : Vec3::Zero();
  // The same fragment still held: it keeps swinging where it was.
  next.held = cur.live && cur.model.held.held && model.held.held ? cur.held : HeldLoadState{};
  init_sides(next, state.scratch);
  if (cur.live && settings.blend_ms > 0) {
    state.blending = true, state.slewing = true, state.blend_weight = 0.0;
  } else {
    state.blending = false, state.blend_weight = 1.0;
    cur.live = false;
  }
  state.newest = target;
  ++state.models_adopted;
}

HapticForce haptic_tick(const HapticTool& model, const Vec3& device_pos_mm,
                        const Vec3& device_vel_mm_s, const HapticSettings& settings,
                        HapticToolState& state) {
  return haptic_tick(model, device_pos_mm, device_vel_mm_s, Vec3::Zero(), settings, state);
}

HapticForce haptic_tick(const HapticTool& model, const Vec3& device_pos_mm,
                        const Vec3& device_vel_mm_s, const Vec3& device_shaft_dir,
                        const HapticSettings& settings, HapticToolState& state) {
  return haptic_tick(model, device_pos_mm, device_vel_mm_s, device_shaft_dir, Vec3::Zero(),
                     settings, state);
}

HapticForce haptic_tick(const HapticTool& model, const Vec3& device_pos_mm,
                        const Vec3& device_vel_mm_s, const Vec3& device_shaft_dir,
                        const Vec3& device_axis_offset_mm, const HapticSettings& settings,
                        HapticToolState& state) {
  HapticForce out;
  ++state.ticks;
  // A shaft that is not a direction (no orientation, or a bad sample) only loses the port.
  const Vec3 shaft = finite(device_shaft_dir) ? device_shaft_dir : Vec3::Zero();
  const Vec3 axis_offset = finite(device_axis_offset_mm) ? device_axis_offset_mm : Vec3::Zero();
  if (!finite(device_pos_mm) || !finite(device_vel_mm_s)) {
    ++state.inputs_rejected;
    out.input_rejected = true;
    return out;
  }
  const HapticSlot& nw = state.slot[state.newest];
  if (&model != &nw.model &&
      (!nw.live || model.present != nw.model.present || model.node_count != nw.model.node_count ||
       model.triangle_count != nw.model.triangle_count ||
       model.grasped_node != nw.model.grasped_node || model.sphere_count != nw.model.sphere_count ||
       model.held.held != nw.model.held.held || model.port_present != nw.model.port_present)) {
    adopt_model(model, state, settings);
  }
  HapticSlot& cur = state.slot[state.newest];
  HapticSlot& old = state.slot[state.newest ^ 1];
  const Vec3 cur_before = cur.force, old_before = old.force;
  tick_slot(cur, state.scratch, device_pos_mm, device_vel_mm_s, shaft, axis_offset, settings,
            state.slot_resets);
  Vec3 f = cur.force;
  out.active = cur.active;
  double natural = (cur.force - cur_before).norm();  // the model's own change this tick
  const double step = settings.blend_ms > 0 ? settings.dt_s / (settings.blend_ms * 1e-3) : 1.0;
  if (old.live && (state.blending || state.slewing)) {
    // The settled model keeps ticking until the output has caught up: its own change is the
    // natural rate the slew bound allows on top (the new model's first ticks are not).
    tick_slot(old, state.scratch, device_pos_mm, device_vel_mm_s, shaft, axis_offset, settings,
              state.slot_resets);
    natural = (old.force - old_before).norm();
  }
  if (state.blending && old.live) {
    state.blend_weight = std::min(1.0, state.blend_weight + step);
    f = (1.0 - state.blend_weight) * old.force + state.blend_weight * cur.force;
    out.active |= kTermBlend;
    if (state.blend_weight >= 1.0) state.blending = false;
  } else {
    state.blending = false, state.blend_weight = 1.0;
  }
  if (state.offset_weight > 0) {
    f += state.offset_weight * state.offset;
    state.offset_weight = std::max(0.0, state.offset_weight - step);
  }
  // Slew bound while a new model settles in: beyond what the models' own motion changes, the
  // output moves by at most blend_max_step_mn per tick (a new model's first ticks can differ
  // from its predecessor's by more than a linear fade over a few ms would hide).
  if (state.slewing && settings.blend_max_step_mn > 0 && finite(f)) {
    const Vec3 delta = f - state.last_force;
    const double cap = settings.blend_max_step_mn + natural, len = delta.norm();
    if (len > cap) {
      f = state.last_force + delta * (cap / len);
      out.active |= kTermBlend;
    } else if (!state.blending && state.offset_weight <= 0) {
      state.slewing = false;
    }
  }
  if (!state.blending && !state.slewing) old.live = false;
  if (!finite(f)) f = Vec3::Zero();
  const double mag = f.norm();
  if (mag > settings.max_force_mn) {
    f *= settings.max_force_mn / mag;
    out.clamped = true;
    ++state.clamped_ticks;
  }
  state.last_force = f, state.last_device = device_pos_mm, state.has_device = true;
  out.force_mn = f;
  out.proxy_mm = cur.proxy;
  out.penetration_mm = cur.penetration_mm;
  out.lens_depth_mm = cur.lens_depth_mm;
  out.sphere_depth_mm = cur.sphere_depth_mm;
  out.held_load_mn = cur.held.load;
  out.blend_weight = state.blend_weight;
  out.solver_iterations = cur.iterations;
  return out;
}

}  // namespace phaco::haptic_model
