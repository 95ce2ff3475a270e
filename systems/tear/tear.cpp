#include "systems/tear/tear.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace phaco::tear {
namespace {

constexpr double kPi = 3.14159265358979323846;

Vec3 radial(const Vec3& p) {
  const Vec3 r(p.x(), p.y(), 0.0);
  const double n = r.norm();
  return n > 1e-12 ? Vec3(r / n) : Vec3::Zero();
}

}  // namespace

std::string_view to_string(TearRule r) {
  return r == TearRule::FlapForce ? "flap_force" : "most_stressed_spring";
}

std::string_view to_string(TearEvent::Kind k) {
  switch (k) {
    case TearEvent::RunoutWarning:
      return "runout_warning";
    case TearEvent::RadialTearout:
      return "radial_tearout";
    default:
      return "completed";
  }
}

double tear_resistance_mn(double tear_energy_j_m2, double thickness_mm) {
  if (!std::isfinite(tear_energy_j_m2) || !std::isfinite(thickness_mm) || tear_energy_j_m2 <= 0 ||
      thickness_mm <= 0)
    throw std::invalid_argument(
        "tear_resistance_mn: the tearing energy and the thickness must be finite and positive");
  return 0.5 * tear_energy_j_m2 * thickness_mm;  // J/m² = mN/mm; × mm = mN
}

uint32_t TearState::count(TearEvent::Kind k) const {
  return static_cast<uint32_t>(
      std::count_if(events.begin(), events.end(), [k](const TearEvent& e) { return e.kind == k; }));
}

RunoutCheck check_runout(const Vec3& tip, const Vec3& direction, const TearSettings& s) {
  RunoutCheck c;
  const Vec3 p(tip.x(), tip.y(), 0.0);
  Vec3 d(direction.x(), direction.y(), 0.0);
  if (d.norm() < 1e-12) return c;
  d.normalize();
  const Vec3 r = radial(tip);
  c.outward_angle_deg = std::asin(std::clamp(d.dot(r), -1.0, 1.0)) * 180.0 / kPi;
  const double R = s.safe_radius_mm, pd = p.dot(d), pp = p.squaredNorm();
  if (pp >= R * R) {
    c.distance_to_safe_edge_mm = 0.0;
  } else {
    c.distance_to_safe_edge_mm = -pd + std::sqrt(pd * pd - (pp - R * R));  // |p + s·d| = R, s > 0
  }
  c.warn =
      c.outward_angle_deg > s.warn_angle_deg || c.distance_to_safe_edge_mm < s.warn_lookahead_mm;
  return c;
}

Vec3 vertex_normal(const cut::CutMesh& m, uint32_t v) {
  std::vector<uint32_t> fan;
  cut::vertex_fan(m.triangles, m.topology.adjacency, m.topology.vertex_triangle[v], v, fan);
  Vec3 n = Vec3::Zero();
  for (uint32_t t : fan) {
    const Vec3 a = cut::particle_position(m.particles, m.triangles.a[t]);
    n += (cut::particle_position(m.particles, m.triangles.b[t]) - a)
             .cross(cut::particle_position(m.particles, m.triangles.c[t]) - a);
  }
  return n.norm() > 0 ? Vec3(n.normalized()) : Vec3(0, 0, 1);
}

Vec3 flap_force_step(const Vec3& tip, const Vec3& normal, const Vec3& c_hat, const Vec3& flap_force,
                     const TearSettings& s) {
  const Vec3 f = flap_force - flap_force.dot(normal) * normal;
  if (f.norm() < s.threshold_mn) return Vec3::Zero();
  Vec3 c = c_hat - c_hat.dot(normal) * normal;
  if (c.norm() > 0) c.normalize();
  Vec3 step = s.a_mm_per_mn * f + s.b_mm * c;
  if (s.outward_bias != 0.0) {
    Vec3 r = radial(tip);
    r -= r.dot(normal) * normal;
    step += s.outward_bias * s.a_mm_per_mn * f.norm() * r;
  }
  const double len = step.norm();
  if (len > s.max_step_mm) step *= s.max_step_mm / len;
  return step;
}

uint32_t most_stressed_spring_end(const cut::CutMesh& m, uint32_t tip, const TearSettings& s) {
  std::vector<uint32_t> fan;
  cut::vertex_fan(m.triangles, m.topology.adjacency, m.topology.vertex_triangle[tip], tip, fan);
  uint32_t best = kInvalidIndex;
  double best_force = -1.0;
  for (uint32_t t : fan) {
    for (int k = 0; k < 3; ++k) {
      const uint32_t n = cut::corner(m.triangles, t, k);
      if (n == tip || !cut::joined_edge(m, tip, n)) continue;
      const auto it = m.topology.spring_of_edge.find(cut::edge_key(tip, n));
      if (it == m.topology.spring_of_edge.end()) continue;
      const double rest = m.springs.rest_length[it->second];
      const double len =
          (cut::particle_position(m.particles, n) - cut::particle_position(m.particles, tip))
              .norm();
      if (rest <= 0 || (len - rest) / rest <= s.break_strain) continue;
      const double force = m.springs.stiffness[it->second] * (len - rest);
      if (force > best_force || (force == best_force && n < best)) best_force = force, best = n;
    }
  }
  return best;
}

Ligament own_ligament(const std::vector<Vec3>& trail, const Vec3& tip) {
  Ligament l;
  double along = 0.0;  // along the trail from the tip back to `prev`
  Vec3 prev = tip;
  for (size_t i = trail.size(); i-- > 0;) {
    const Vec3 ab = trail[i] - prev;
    const double len2 = ab.squaredNorm(), len = std::sqrt(len2);
    const double t = len2 > 0 ? std::clamp((tip - prev).dot(ab) / len2, 0.0, 1.0) : 0.0;
    const Vec3 q = prev + t * ab;
    const double d = (tip - q).norm(), s = along + t * len;
    if (s > 0.0 && s >= kLigamentCurl * d && (!l.found || d < l.width_mm)) l = {true, d, q};
    along += len, prev = trail[i];
  }
  return l;
}

namespace {

// Whether the flap's pull breaks the ligament to the path's own start (tear.hpp), and where the
// tear then runs: through the ligament's nearest point and a little beyond (half its width and two
// vertex snaps), so that the cut meets the earlier cut's lip rather than stopping short of it.
bool ligament_breaks(const cut::CutMesh& m, const cut::CutPath& path, const TearState& state,
                     const Vec3& tip_x, const Vec3& flap_force, const TearSettings& tear,
                     const cut::CutSettings& cut, Vec3& target) {
  if (!(tear.ligament_strength_mn_per_mm > 0.0)) return false;
  const Vec3 n = vertex_normal(m, path.tip);
  const double pull = (flap_force - flap_force.dot(n) * n).norm();
  if (!(pull > 0.0)) return false;
  const Ligament l = own_ligament(state.trail, tip_x);
  // A sliver: within one tear step of the start (what the flap-force rule crosses in one step).
  if (!l.found || l.width_mm > tear.max_step_mm) return false;
  // The flap's tension at the tip is the tear's plateau at most: the pull beyond F_c drags the
  // disc.
  if (std::min(pull, tear.threshold_mn) < tear.ligament_strength_mn_per_mm * l.width_mm)
    return false;
  const Vec3 across = l.to - tip_x;
  const Vec3 dir = across.norm() > 1e-12 ? Vec3(across.normalized()) : path.direction;
  target = l.to + (0.5 * l.width_mm + 2.0 * cut.snap.vertex_snap_mm) * dir;
  return true;
}

}  // namespace

TearStepReport tear_step(cut::CutMesh& m, cut::CutPath& path, TearState& state,
                         const Vec3& flap_force, const TearSettings& tear,
                         const cut::CutSettings& cut, cut::EditLog& log) {
  if (path.tip == kInvalidIndex || !m.particles.slots.alive(path.tip))
    throw std::invalid_argument("tear_step: the path has no tip (puncture and cut a flap first)");
  if (!flap_force.allFinite())
    throw std::invalid_argument("tear_step: the flap force is not finite");
  TearStepReport r;
  if (state.complete || path.reached_boundary) return r;
  ++state.steps;
  const uint32_t tip = path.tip;
  const Vec3 x = cut::particle_position(m.particles, tip);
  if (state.trail.empty()) {  // the path before the tear: from its first vertex to the tip
    const uint32_t first = path.sources.empty() ? tip : path.sources.front();
    state.trail.push_back(
        cut::particle_position(m.particles, m.particles.slots.alive(first) ? first : tip));
    state.trail.push_back(x);
  }
  Vec3 target;
  if (ligament_breaks(m, path, state, x, flap_force, tear, cut, target)) {
    r.ligament_broke = true;
    r.advance_mm = (target - x).norm();
  } else if (tear.rule == TearRule::FlapForce) {
    const Vec3 step = flap_force_step(x, vertex_normal(m, tip), path.direction, flap_force, tear);
    if (step.norm() == 0.0) return r;
    r.advance_mm = step.norm();
    // The tear front runs ahead of the tip while snapping keeps the tip waiting for a good split.
    // (The membrane moves: a front left far behind by the tip's motion starts again at the tip.)
    if (!state.front_valid || (state.front - x).norm() > 4.0 * tear.max_step_mm) state.front = x;
    state.front_valid = true;
    state.front += step;
    target = state.front;
  } else {
    const uint32_t n = most_stressed_spring_end(m, tip, tear);
    if (n == kInvalidIndex) return r;
    target = cut::particle_position(m.particles, n);
    r.advance_mm = (target - x).norm();
  }
  const RunoutCheck check = check_runout(x, target - x, tear);
  if (check.warn && state.warning_armed) {
    state.events.push_back({TearEvent::RunoutWarning, state.steps, std::hypot(x.x(), x.y()),
                            check.outward_angle_deg, x});
    state.warning_armed = false;
    r.warned = true;
  } else if (!check.warn) {
    state.warning_armed = true;
  }
  r.segment = cut::cut_towards(m, path, target, cut, log);
  if (r.ligament_broke && !r.segment.made) r.advance_mm = 0.0;  // no way through: nothing moved
  if (r.segment.made) {
    r.advanced = true;
    ++state.advances;
    const Vec3 now = cut::particle_position(m.particles, path.tip);
    state.trail.push_back(now);
    if ((now - state.front).norm() <= cut.snap.vertex_snap_mm || tear.rule != TearRule::FlapForce ||
        r.ligament_broke)
      state.front = now;
    const double radius = std::hypot(now.x(), now.y());
    state.max_radius_mm = std::max(state.max_radius_mm, radius);
    if (radius > tear.safe_radius_mm && !state.torn_out) {
      state.torn_out = true;
      r.torn_out = true;
      state.events.push_back(
          {TearEvent::RadialTearout, state.steps, radius, check.outward_angle_deg, now});
    }
  }
  if (r.segment.reached_boundary) {
    state.complete = true;
    r.completed = true;
    const Vec3 now = cut::particle_position(m.particles, path.tip);
    state.events.push_back({TearEvent::Completed, state.steps, std::hypot(now.x(), now.y()),
                            check.outward_angle_deg, now});
  }
  return r;
}

TearRunReport tear_until_below(cut::CutMesh& m, cut::CutPath& path, TearState& state,
                               const Vec3& flap_force, double elongation_mm,
                               const TearSettings& tear, const cut::CutSettings& cut,
                               cut::EditLog& log) {
  TearRunReport run;
  run.force_before_mn = run.force_after_mn = flap_force.norm();
  const double e =
      std::isfinite(elongation_mm) && elongation_mm > 0 ? elongation_mm : tear.max_step_mm;
  Vec3 f = flap_force;
  while (run.steps < tear.max_steps && run.advance_mm < tear.max_advance_mm) {
    const TearStepReport r = tear_step(m, path, state, f, tear, cut, log);
    run.warned |= r.warned, run.torn_out |= r.torn_out, run.completed |= r.completed;
    if (r.advance_mm <= 0.0) break;  // below the resistance, or nothing left to tear
    ++run.steps;
    run.advance_mm += r.advance_mm;
    f = flap_force * std::max(0.0, 1.0 - run.advance_mm / e);
    run.force_after_mn = f.norm();
    if (r.completed || state.complete || path.reached_boundary) break;
  }
  return run;
}

}  // namespace phaco::tear
