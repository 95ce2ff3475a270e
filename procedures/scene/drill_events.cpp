// The drill's record while it runs: per frame and per hand, the samples and the events (the
// detectors of drill_metrics.hpp), and the trainer's live view of the events.
#include <algorithm>
#include <cmath>

#include "components/particles.hpp"
#include "procedures/scene/capsule_cutting.hpp"
#include "procedures/scene/capsule_physics.hpp"
#include "procedures/scene/drill_metrics.hpp"
#include "procedures/scene/drill_record.hpp"
#include "procedures/scene/scene.hpp"
#include "procedures/scene/tool_ports.hpp"
#include "systems/deform/spring_law.hpp"
#include "systems/grasp/grasp.hpp"
#include "systems/haptic_model/haptic_model.hpp"

namespace phaco {

namespace {

constexpr double kClosedGrip = grasp::GraspSettings{}.close_at;  // forceps closed, as systems/grasp

Anatomy anatomy_of(const eye::EyeParams& p) {
  Anatomy a;
  a.lens.lens_present = true;
  a.lens.lens_centre_mm = {0.0f, 0.0f, 0.0f};  // the origin is the lens's equatorial centre (§6)
  a.lens.lens_equator_radius_mm = static_cast<float>(0.5 * p.get("lens.equatorial_diameter_mm"));
  a.lens.lens_anterior_mm = static_cast<float>(p.get("lens.anterior_half_thickness_mm"));
  a.lens.lens_posterior_mm = static_cast<float>(p.get("lens.posterior_half_thickness_mm"));
  a.lens_stiffness_mn_mm = p.get("haptic_model.lens_stiffness_mn_mm");
  a.iris_z_mm = p.get("iris.z_mm");
  a.pupil_radius_mm = 0.5 * p.get("iris.pupil_diameter_mm");
  a.limbus_radius_mm = 0.5 * p.get("cornea.limbus_diameter_mm");
  a.cornea_posterior_radius_mm = p.get("cornea.posterior_radius_mm");
  a.cornea_centre = {0.0, 0.0, p.get("cornea.posterior_apex_z_mm") - a.cornea_posterior_radius_mm};
  // The wound is about a keratome blade wide: within a blade's width of the entry point the tip
  // is in the incision, not pressing the endothelium.
  a.port_radius_mm = p.get("tools.keratome_width_mm");
  a.phaco_tip_radius_mm = 0.5 * p.get("tools.phaco_tip_diameter_mm");
  a.cystotome_tip_mm = p.get("tools.cystotome_tip_mm");
  a.capsule_half_thickness_mm = 0.5 * p.get("capsule.thickness_mm");
  return a;
}

// |Σ spring forces| on the particle the forceps hold: the flap's pull on the tool, mN.
double held_pull_mn(const Particles& p, const CapsuleSprings& cp, SpringLaw law, uint32_t held) {
  if (held >= cp.graph.particle_count() || !p.slots.alive(held)) return 0.0;
  const Vec3 x(p.x[held], p.y[held], p.z[held]);
  Vec3 f = Vec3::Zero();
  for (uint32_t k = cp.graph.begin(held); k < cp.graph.end(held); ++k) {
    const uint32_t n = cp.graph.neighbour[k], s = cp.graph.spring[k];
    const Vec3 d = Vec3(p.x[n], p.y[n], p.z[n]) - x;
    const double len = d.norm();
    if (len <= 0) continue;
    const float mag = deform::spring_magnitude(law, cp.springs.stiffness[s],
                                               static_cast<float>(len - cp.springs.rest_length[s]));
    f += static_cast<double>(mag) * (d / len);
  }
  return f.norm();
}

// One sample of one hand at time t (the end of a frame); `dt_s` 0 for the t = 0 sample.
void sample_hand(Scene& scene, DrillRecord& r, int index, double t, double dt_s) {
  HandRecord& h = r.hands[static_cast<size_t>(index)];
  const Anatomy& a = r.anatomy;
  const ToolState& pose = scene.world.at<ToolState>(h.tool);
  const Vec3 p = pose.pos;
  const Vec3 previous = h.pos.empty() ? p : h.pos.back();
  const double speed = metrics::add_position(h.kinematics, p, dt_s);

  // Where forceps first close, on tissue or not: grasp.offset_mm from the drill's grasp site.
  if (h.kind == ToolKind::Forceps && !r.first_grasp && pose.grip >= kClosedGrip) r.first_grasp = p;

  // Grasp events from the forceps' capsule grasp state (systems/grasp's hysteresis).
  double force = 0.0;
  bool tearing = false;
  if (const ToolGrasp* g = scene.world.get<ToolGrasp>(h.tool)) {
    const bool holding = g->capsule.holding(), closed = g->capsule.closed;
    if (closed && !h.closed) {
      if (holding) {
        ++h.grasps, push_event(r, t, "grasp", index);
      } else {
        ++h.missed_grasps, push_event(r, t, "missed_grasp", index);
      }
    } else if (holding && !h.holding) {
      ++h.grasps, push_event(r, t, "grasp", index);
    }
    if (h.holding && !holding) ++h.releases, push_event(r, t, "release", index);
    h.closed = closed, h.holding = holding;
    if (holding) {
      const Entity capsule = *scene.body(BodyPart::Capsule);
      force =
          held_pull_mn(scene.world.at<Particles>(capsule), scene.world.at<CapsuleSprings>(capsule),
                       scene.world.at<CapsuleSettings>(capsule).dynamics.law, g->capsule.particle);
      const CapsuleCutting* cc = scene.world.get<CapsuleCutting>(capsule);
      tearing = cc && cc->tearing;
    }
  }

  // Lens: the tip point in the two half-ellipsoids; seed 003's k_f·d when nothing is held.
  const haptic_model::LensContact lc = haptic_model::lens_penetration(a.lens, p, 0.0);
  // The capsule lies on the lens, its mid-surface on the lens's surface: a tip within its half
  // thickness (6.5 µm) is in the capsule, e.g. forceps closing on it with a hand's tremor. The
  // cystotome must pierce it: its tip in the cortex by up to its own size is the puncture.
  const double allowance =
      h.kind == ToolKind::Cystotome ? a.cystotome_tip_mm : a.capsule_half_thickness_mm;
  const bool in_lens = lc.depth_mm > allowance;
  if (in_lens && !h.in_lens)
    ++h.lens_contacts, push_event(r, t, "lens_contact", index, "depth_mm", lc.depth_mm);
  h.in_lens = in_lens;
  if (force == 0.0 && lc.depth_mm > 0) force = a.lens_stiffness_mn_mm * lc.depth_mm;

  // Iris: the path this frame crosses the iris plane outside the pupil (and inside the limbus).
  const double z0 = previous.z() - a.iris_z_mm, z1 = p.z() - a.iris_z_mm;
  if ((z0 > 0 && z1 <= 0) || (z0 <= 0 && z1 > 0)) {
    const double s = z0 / (z0 - z1);
    const Vec3 c = previous + s * (p - previous);
    const double rho = std::hypot(c.x(), c.y());
    if (rho > a.pupil_radius_mm && rho < a.limbus_radius_mm)
      ++h.iris_contacts, push_event(r, t, "iris_contact", index, "radius_mm", rho);
  }

  // Cornea: the first point behind its posterior sphere is the wound; later, the tip beyond that
  // sphere inside the limbus and away from the wound presses the endothelium.
  const bool inside_cornea = (p - a.cornea_centre).norm() < a.cornea_posterior_radius_mm;
  if (!h.entered_eye) {
    if (inside_cornea) h.entered_eye = true, h.port = p;
  } else {
    const bool beyond = !inside_cornea && std::hypot(p.x(), p.y()) < a.limbus_radius_mm &&
                        (p - h.port).norm() > a.port_radius_mm;
    if (beyond && !h.beyond_cornea) ++h.corneal_stress, push_event(r, t, "corneal_stress", index);
    h.beyond_cornea = beyond;
  }

  // Posterior capsule: the phaco tip's sphere reaching the lens's posterior surface — its centre
  // within a tip radius of that surface (inside) or beyond it.
  if (h.kind == ToolKind::PhacoProbe) {
    const bool breach = lc.nearest_mm.z() < 0.0 && lc.signed_distance_mm > -a.phaco_tip_radius_mm;
    if (breach && !h.breach) ++h.capsule_breaches, push_event(r, t, "capsule_breach", index);
    h.breach = breach;
  }

  if (dt_s > 0) h.force.add(force);
  if (dt_s > 0 && tearing) h.tear_force.add(force), h.tearing_s += dt_s;
  h.tearing.push_back(tearing ? 1 : 0);
  h.pos.push_back(p);
  h.speed_mm_s.push_back(speed);
  h.force_mn.push_back(force);
}

// Tear events of the capsule's tear front, as they happen.
void sample_tear(Scene& scene, DrillRecord& r, double t) {
  const auto capsule = scene.body(BodyPart::Capsule);
  if (!capsule) return;
  const CapsuleCutting* cc = scene.world.get<CapsuleCutting>(*capsule);
  if (!cc) return;
  // A tool pressing the rhexis rim started a tear, or one ran to the equator (rim_tear.hpp).
  for (; r.rim_events_seen < cc->rim.events.size(); ++r.rim_events_seen) {
    const RimTearEvent& e = cc->rim.events[r.rim_events_seen];
    push_event(r, t, e.kind, static_cast<int>(e.tool), e.detail, e.value);
  }
  if (!r.puncture && cc->cut_segments > 0) {
    for (const HandRecord& h : r.hands)
      if (h.kind == ToolKind::Cystotome) r.puncture = scene.world.at<ToolState>(h.tool).pos;
  }
  const tear::TearState& ts = cc->tear_state;
  int holder = -1;
  for (size_t i = 0; i < r.hands.size(); ++i)
    if (r.hands[i].holding) holder = static_cast<int>(i);
  // A new flap restarts the tear state: its events are counted from its start.
  if (ts.events.size() < r.tear_events_seen) r.tear_events_seen = 0;
  for (; r.tear_events_seen < ts.events.size(); ++r.tear_events_seen) {
    const tear::TearEvent& e = ts.events[r.tear_events_seen];
    const char* kind = e.kind == tear::TearEvent::RunoutWarning   ? "runout_warning"
                       : e.kind == tear::TearEvent::RadialTearout ? "radial_tearout"
                                                                  : "tear_complete";
    push_event(r, t, kind, holder, "radius_mm", e.radius_mm);
  }
}

}  // namespace

DrillRecord* record_of(Scene& scene) {
  return scene.bodies.empty() ? nullptr : scene.world.get<DrillRecord>(scene.bodies.front());
}

void push_event(DrillRecord& r, double t, const char* kind, int hand, const char* detail,
                double value) {
  r.events.push_back({t, kind, hand, detail, value});
}

SystemDesc drill_metrics_system(Scene& scene) {
  DrillRecord r;
  r.anatomy = anatomy_of(scene.params);
  const uint64_t samples = scene.scenario.frame_count() + 1;
  r.t_s.reserve(samples);
  r.events.reserve(256);
  for (Entity e : scene.tools) {
    HandRecord h;
    h.tool = e;
    h.hand = scene.world.at<Tool>(e).hand;
    h.kind = scene.world.at<Tool>(e).kind;
    h.pos.reserve(samples), h.speed_mm_s.reserve(samples), h.force_mn.reserve(samples);
    h.tearing.reserve(samples);
    r.hands.push_back(std::move(h));
  }
  if (scene.scenario.drill == Drill::NucleusRemoval) r.nucleus = make_nucleus_removal_record(scene);
  // The t = 0 sample: the tools' poses the scene starts from.
  r.t_s.push_back(0.0);
  for (size_t i = 0; i < r.hands.size(); ++i) sample_hand(scene, r, static_cast<int>(i), 0.0, 0.0);
  scene.world.name_component<DrillRecord>("metrics", AccessKind::Global);
  if (!scene.bodies.empty()) scene.world.add(scene.bodies.front(), std::move(r));
  return {
      .name = "drill_metrics",
      .phase = Phase::Metrics,
      .reads = {"tools.pose", "tools.grasp", "capsule.particles", "capsule.springs",
                "capsule.settings", "capsule.cutting", "lens.tets", "lens.cells", "tools.ports"},
      .writes = {"metrics"},
      .after = {},
      .run = [&scene](const FrameContext& ctx) {
        DrillRecord* rec = record_of(scene);
        if (!rec) return;
        const double t = ctx.time_s + ctx.dt_s;  // the poses are those at the frame's end
        rec->t_s.push_back(t);
        for (size_t i = 0; i < rec->hands.size(); ++i)
          sample_hand(scene, *rec, static_cast<int>(i), t, ctx.dt_s);
        sample_tear(scene, *rec, t);
        if (rec->nucleus) {
          const uint32_t ruptured = sample_nucleus_removal(scene, *rec->nucleus, ctx.dt_s);
          for (size_t i = 0; i < rec->hands.size(); ++i)
            if (ruptured & (1u << i))
              push_event(*rec, t, "posterior_capsule_rupture", static_cast<int>(i));
        }
        // The tool pressing its corneal port beyond the threshold (tool_ports.hpp; ports on
        // only).
        for (size_t i = 0; i < rec->hands.size(); ++i) {
          if (double f = 0; port_stress_began(scene, i, f))
            push_event(*rec, t, "port_stress", static_cast<int>(i), "force_mN", f);
        }
      }};
}

size_t drill_event_count(Scene& scene) {
  const DrillRecord* r = record_of(scene);
  return r ? r->events.size() : 0;
}

LiveDrillEvent drill_event(Scene& scene, size_t index) {
  const DrillRecord& r = *record_of(scene);
  const DrillEvent& e = r.events.at(index);
  const int hand = e.hand < 0 ? -1 : static_cast<int>(r.hands[static_cast<size_t>(e.hand)].hand);
  return {e.t_s, e.kind, hand, e.detail, e.value};
}

}  // namespace phaco
