#include "procedures/scene/drill_metrics.hpp"

#include <algorithm>
#include <cmath>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "components/haptic_model.hpp"
#include "components/particles.hpp"
#include "components/tool.hpp"
#include "components/triangles.hpp"
#include "procedures/rhexis/opening.hpp"
#include "procedures/scene/capsule_cutting.hpp"
#include "procedures/scene/capsule_physics.hpp"
#include "procedures/scene/cornea_cutting.hpp"
#include "procedures/scene/lens_sculpting.hpp"
#include "procedures/scene/nucleus_removal_metrics.hpp"
#include "procedures/scene/scene.hpp"
#include "procedures/scene/tool_ports.hpp"
#include "systems/deform/spring_law.hpp"
#include "systems/grasp/grasp.hpp"
#include "systems/haptic_model/haptic_model.hpp"
#include "systems/metrics/metrics.hpp"

namespace phaco {

namespace {

constexpr uint32_t kHistogramBins = 20;
constexpr double kClosedGrip = grasp::GraspSettings{}.close_at;  // forceps closed, as systems/grasp

struct DrillEvent {
  double t_s = 0;
  const char* kind = "";
  int hand = -1;                 // index into DrillRecord::hands, −1: the drill's
  const char* detail = nullptr;  // name of `value`, if any
  double value = 0;
};

struct HandRecord {
  Entity tool;
  Hand hand = Hand::Right;
  ToolKind kind = ToolKind::Forceps;
  std::vector<Vec3> pos;  // per sample (t = 0, then the end of every frame)
  std::vector<double> speed_mm_s, force_mn;
  metrics::Kinematics kinematics;
  metrics::RunningStats force;  // over the frames (not the t = 0 sample)
  // Frames in which these forceps hold the flap of an open tear (CapsuleCutting::tearing), and the
  // force over them: the tear's plateau (issue 17 item 5).
  std::vector<uint8_t> tearing;
  metrics::RunningStats tear_force;
  double tearing_s = 0;
  // Event state.
  bool closed = false, holding = false, in_lens = false, beyond_cornea = false, breach = false;
  bool entered_eye = false;
  Vec3 port = Vec3::Zero();  // where the tip first went behind the cornea: the incision
  uint64_t grasps = 0, releases = 0, missed_grasps = 0, lens_contacts = 0, iris_contacts = 0;
  uint64_t corneal_stress = 0, capsule_breaches = 0;
};

// The scene's geometry the detectors test against (DESIGN.md §6, the eye parameters).
struct Anatomy {
  HapticTool lens;                  // only its lens_* fields: lens_penetration's input
  double lens_stiffness_mn_mm = 0;  // seed 003's k_f
  double iris_z_mm = 0, pupil_radius_mm = 0, limbus_radius_mm = 0;
  Vec3 cornea_centre = Vec3::Zero();
  double cornea_posterior_radius_mm = 0;
  double port_radius_mm = 0;  // a tip this close to where it entered is in the wound
  double phaco_tip_radius_mm = 0;
  double cystotome_tip_mm = 0;
};

struct DrillRecord {
  Anatomy anatomy;
  std::vector<HandRecord> hands;
  std::vector<double> t_s;
  std::vector<DrillEvent> events;
  size_t tear_events_seen = 0;
  std::optional<Vec3> first_grasp;              // where forceps first closed (grasp.offset_mm)
  std::optional<Vec3> puncture;                 // the cystotome's tip when it first cut the capsule
  std::optional<NucleusRemovalRecord> nucleus;  // the nucleus_removal drill's measures
};

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
  return a;
}

DrillRecord* record_of(Scene& scene) {
  return scene.bodies.empty() ? nullptr : scene.world.get<DrillRecord>(scene.bodies.front());
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

void push_event(DrillRecord& r, double t, const char* kind, int hand, const char* detail = nullptr,
                double value = 0) {
  r.events.push_back({t, kind, hand, detail, value});
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
  // The cystotome must pierce the capsule lying on the lens: its tip in the cortex by up to its own
  // size is the puncture, not a lens hit.
  const double allowance = h.kind == ToolKind::Cystotome ? a.cystotome_tip_mm : 0.0;
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

nlohmann::json band(std::optional<double> lo, std::optional<double> hi) {
  nlohmann::json j = nlohmann::json::object();
  if (lo) j["min"] = *lo;
  if (hi) j["max"] = *hi;
  return j;
}

nlohmann::json xyz(const Vec3& v) {
  return nlohmann::json::array({v.x(), v.y(), v.z()});
}

// Depth of a removed element's centre below the anterior surface, as a fraction of the thickness
// there: the nucleus's where the centre is above it, else the lens's (the cortex).
double depth_fraction(const lens::NucleusShape& n, const Anatomy& a, const Vec3& c) {
  double top = lens::nucleus_anterior_z(n, c.x(), c.y()),
         bottom = lens::nucleus_posterior_z(n, c.x(), c.y());
  if (!std::isfinite(top) || !std::isfinite(bottom)) {
    const double rr = (c.x() * c.x() + c.y() * c.y()) / (double(a.lens.lens_equator_radius_mm) *
                                                         double(a.lens.lens_equator_radius_mm));
    const double s = std::sqrt(std::max(0.0, 1.0 - rr));
    top = a.lens.lens_anterior_mm * s, bottom = -a.lens.lens_posterior_mm * s;
  }
  return top > bottom ? (top - c.z()) / (top - bottom) : 0.0;
}

// The drill file's score terms (docs/scoring.md) against the targets in `out`. A step not
// attempted scores 0 (its safety terms included: "no contact" is no skill when nothing was done);
// a complication fails the drill and caps its score.
void score(DrillReport& out, const DrillFile& drill) {
  const auto number = [&out](const std::string& metric) {
    return out.metrics.contains(metric) && out.metrics[metric].is_number()
               ? std::optional<double>(out.metrics[metric].get<double>())
               : std::nullopt;
  };
  out.attempted = drill.attempted_if_any.empty();
  for (const std::string& m : drill.attempted_if_any) out.attempted |= number(m).value_or(0.0) > 0;
  for (const ScoreTerm& t : drill.scoring) {
    const nlohmann::json value =
        out.metrics.contains(t.metric) ? out.metrics[t.metric] : nlohmann::json();
    const nlohmann::json target =
        out.targets.contains(t.metric) ? out.targets[t.metric] : nlohmann::json::object();
    const double points = out.attempted ? band_points(value, target, t.falloff, t.weight) : 0.0;
    out.score_terms.push_back({{"metric", t.metric},
                               {"value", value},
                               {"target", target},
                               {"weight", t.weight},
                               {"points", points}});
    out.score += points;
  }
  out.score = std::clamp(out.score, 0.0, 100.0);
  for (const Complication& c : drill.complications) {
    const auto v = number(c.metric);
    if (!v || *v <= c.above) continue;
    out.complications.push_back(
        {{"name", c.name}, {"metric", c.metric}, {"value", *v}, {"score_cap", c.score_cap}});
    out.score = std::min(out.score, c.score_cap);
  }
  out.metrics["attempted"] = out.attempted ? 1 : 0;
  out.metrics["drill_failed"] = out.complications.empty() ? 0 : 1;
}

void hand_metrics(const Scene& scene, const DrillRecord& r, DrillReport& out,
                  const std::vector<size_t>& idx) {
  nlohmann::json hands = nlohmann::json::object();
  for (const HandRecord& h : r.hands) {
    const std::string name(to_string(h.hand));
    const auto& k = h.kinematics;
    out.metrics[name + ".path_length_mm"] = k.path_length_mm;
    out.metrics[name + ".tool_speed_mm_s.mean"] = k.speed_mm_s.mean;
    out.metrics[name + ".tool_speed_mm_s.std"] = k.speed_mm_s.stddev();
    out.metrics[name + ".tool_speed_mm_s.max"] = k.speed_mm_s.max;
    out.metrics[name + ".contact_force_mN.mean"] = h.force.mean;
    out.metrics[name + ".contact_force_mN.std"] = h.force.stddev();
    out.metrics[name + ".contact_force_mN.max"] = h.force.max;
    if (h.tear_force.count > 0) {  // forceps that tore: the force over the tearing frames
      const auto& f = h.tear_force;
      out.metrics[name + ".tear_force_mN.rms"] = std::sqrt(f.mean * f.mean + f.variance());
      out.metrics[name + ".tear_force_mN.mean"] = f.mean;
      out.metrics[name + ".tear_force_mN.max"] = f.max;
      out.metrics[name + ".tearing_s"] = h.tearing_s;
    }
    nlohmann::json s;
    s["tool"] = std::string(to_string(h.kind));
    nlohmann::json pos = nlohmann::json::array(), speed = nlohmann::json::array(),
                   force = nlohmann::json::array(), tearing = nlohmann::json::array();
    for (size_t i : idx) {
      pos.push_back(xyz(h.pos[i]));
      speed.push_back(h.speed_mm_s[i]);
      force.push_back(h.force_mn[i]);
      tearing.push_back(h.tearing[i]);
    }
    s["pos_mm"] = std::move(pos);
    s["speed_mm_s"] = std::move(speed);
    s["force_mN"] = std::move(force);
    if (h.tear_force.count > 0)
      s["tearing"] = std::move(tearing);  // 1: holding an open tear's flap
    // Seed 000 Fig. 11: the distributions over every frame (not the decimated series).
    const std::span<const double> frames_speed(h.speed_mm_s.data() + 1, h.speed_mm_s.size() - 1);
    const std::span<const double> frames_force(h.force_mn.data() + 1, h.force_mn.size() - 1);
    const metrics::Histogram hs = metrics::histogram_from_zero(frames_speed, kHistogramBins);
    const metrics::Histogram hf = metrics::histogram_from_zero(frames_force, kHistogramBins);
    s["speed_histogram"] = {{"edges_mm_s", hs.edges()}, {"counts", hs.counts}};
    s["force_histogram"] = {{"edges_mN", hf.edges()}, {"counts", hf.counts}};
    hands[name] = std::move(s);
  }
  (void)scene;
  out.series["hands"] = std::move(hands);
}

void capsulorhexis_metrics(Scene& scene, const DrillRecord& r, DrillReport& out) {
  uint64_t grasps = 0;
  for (const HandRecord& h : r.hands) grasps += h.grasps;
  out.metrics["grasps"] = grasps;
  out.metrics["regrasps"] = grasps > 0 ? grasps - 1 : 0;  // the first grasp is not a regrasp
  if (r.puncture && scene.drill.guidance.puncture_site_mm) {
    out.metrics["rhexis.puncture_offset_mm"] =
        (*r.puncture - *scene.drill.guidance.puncture_site_mm).norm();
  }
  const auto capsule = scene.body(BodyPart::Capsule);
  const CapsuleCutting* cc = capsule ? scene.world.get<CapsuleCutting>(*capsule) : nullptr;
  if (!cc) {
    out.metrics["rhexis.complete"] = 0;
    return;
  }
  // Counted from the recorded events: a new cystotome stroke restarts the tear's own state, the
  // record keeps every flap's.
  uint64_t tearouts = 0, warnings = 0;
  for (const DrillEvent& e : r.events) {
    tearouts += std::string_view(e.kind) == "radial_tearout";
    warnings += std::string_view(e.kind) == "runout_warning";
  }
  out.metrics["capsule.cut_segments"] = cc->cut_segments;
  out.metrics["rhexis.radial_tearouts"] = tearouts;
  out.metrics["runout_warnings"] = warnings;
  CapsuleSprings& cp = scene.world.at<CapsuleSprings>(*capsule);
  CapsuleCutting& ccm = scene.world.at<CapsuleCutting>(*capsule);
  const cut::CutMesh m{scene.world.at<Particles>(*capsule), scene.world.at<Triangles>(*capsule),
                       cp.springs, ccm.topology, ccm.material};
  const rhexis::Opening o = rhexis::measure_opening(m);
  out.metrics["rhexis.complete"] = o.complete ? 1 : 0;
  if (!o.complete) return;
  out.metrics["rhexis.diameter_mm"] = o.diameter_mm;
  out.metrics["rhexis.circularity"] = o.circularity;
  out.metrics["rhexis.centering_mm"] = o.centering_mm;
  out.metrics["rhexis.ellipse_diameter_mm"] = o.ellipse_diameter_mm;
  out.metrics["rhexis.ellipse_axis_ratio"] = o.ellipse_axis_ratio;
  nlohmann::json outline = nlohmann::json::array();
  for (const auto& q : o.outline_mm) outline.push_back({q[0], q[1]});
  out.series["rhexis"] = {{"outline_mm", std::move(outline)}};
  if (out.targets.contains("rhexis.diameter_mm")) {
    const nlohmann::json& d = out.targets["rhexis.diameter_mm"];
    out.series["rhexis"]["target_diameter_mm"] = {d.value("min", 0.0), d.value("max", 0.0)};
  }
  const auto& circle = scene.drill.guidance.rhexis_circle;
  out.series["rhexis"]["target_centre_mm"] = {circle ? circle->centre_mm.x() : 0.0,
                                              circle ? circle->centre_mm.y() : 0.0};
}

void sculpting_metrics(Scene& scene, const DrillRecord& r, DrillReport& out) {
  uint64_t breaches = 0, iris = 0;
  for (const HandRecord& h : r.hands) breaches += h.capsule_breaches, iris += h.iris_contacts;
  out.metrics["capsule_breach"] = breaches > 0 ? 1 : 0;
  out.metrics["iris_contacts"] = iris;
  // Each trench is held to the drill's trench targets.
  const nlohmann::json width = out.targets.value("trench.width_mm", nlohmann::json::object());
  const nlohmann::json depth = out.targets.value("trench.depth_fraction", nlohmann::json::object());
  const auto lens = scene.body(BodyPart::Lens);
  const LensSculpting* ls = lens ? scene.world.get<LensSculpting>(*lens) : nullptr;
  if (!ls) return;
  out.metrics["tets_removed"] = ls->topology.tet_count - ls->topology.alive_count;
  out.metrics["volume_removed_mm3"] = ls->volume_removed_mm3;
  out.metrics["ultrasound_time_s"] = ls->ultrasound_time_s;
  const lens::TrenchReport tr = lens_trenches(scene);
  out.metrics["trench.count"] = tr.trenches.size();
  if (!tr.trenches.empty()) {
    double w = 0, d = 0;
    for (size_t i = 0; i < tr.trenches.size(); ++i) {
      const std::string key = "trench." + std::to_string(i);
      out.metrics[key + ".width_mm"] = tr.trenches[i].width_mm;
      out.metrics[key + ".depth_fraction"] = tr.trenches[i].depth_fraction;
      out.targets[key + ".width_mm"] = width;
      out.targets[key + ".depth_fraction"] = depth;
      w += tr.trenches[i].width_mm, d += tr.trenches[i].depth_fraction;
    }
    out.metrics["trench.width_mm"] = w / double(tr.trenches.size());
    out.metrics["trench.depth_fraction"] = d / double(tr.trenches.size());
  }
  if (tr.trenches.size() >= 2) out.metrics["trench.crossing_angle_deg"] = tr.crossing_angle_deg;
  const auto idx = metrics::decimation_indices(ls->removed.size(), metrics::kMaxSeriesSamples);
  nlohmann::json removed = nlohmann::json::array();
  for (size_t i : idx) {
    const Vec3& c = ls->removed[i].centre;
    removed.push_back({c.x(), c.y(), depth_fraction(ls->nucleus, r.anatomy, c)});
  }
  out.series["trench"] = {{"removed_xy_depth", std::move(removed)},
                          {"nucleus_radius_mm", ls->nucleus.equatorial_radius_mm},
                          {"frame", "lens"}};
}

}  // namespace

double band_points(const nlohmann::json& value, const nlohmann::json& target, double falloff,
                   double weight) {
  if (!value.is_number()) return 0.0;
  const double v = value.get<double>();
  double outside = 0.0;
  if (target.contains("min")) outside = std::max(outside, target["min"].get<double>() - v);
  if (target.contains("max")) outside = std::max(outside, v - target["max"].get<double>());
  if (outside <= 0.0) return weight;
  if (falloff <= 0.0) return 0.0;
  return weight * std::max(0.0, 1.0 - outside / falloff);
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

DrillReport drill_report(Scene& scene) {
  DrillReport out;
  const DrillRecord* r = record_of(scene);
  if (!r) return out;
  out.metrics["time_s"] = scene.time_s;
  uint64_t stress = 0, lens = 0;
  for (const HandRecord& h : r->hands) stress += h.corneal_stress, lens += h.lens_contacts;
  out.metrics["corneal_stress_events"] = stress;
  out.metrics["lens_contacts"] = lens;  // a tip entering the lens (every drill: an attempt)
  // Targets are the drill file's (data/drills); the per-trench ones derive from them.
  for (const auto& [name, b] : scene.drill.targets) out.targets[name] = band(b.min, b.max);
  if (r->first_grasp && scene.drill.guidance.grasp_site_mm) {
    out.metrics["grasp.offset_mm"] = (*r->first_grasp - *scene.drill.guidance.grasp_site_mm).norm();
  }

  const auto idx = metrics::decimation_indices(r->t_s.size(), metrics::kMaxSeriesSamples);
  out.series["t_s"] = metrics::decimate<double>(r->t_s, idx);
  hand_metrics(scene, *r, out, idx);

  switch (scene.scenario.drill) {
    case Drill::Capsulorhexis:
      capsulorhexis_metrics(scene, *r, out);
      break;
    case Drill::PhacoSculpting:
      sculpting_metrics(scene, *r, out);
      break;
    case Drill::NucleusRemoval: {
      uint64_t iris = 0;
      for (const HandRecord& h : r->hands) iris += h.iris_contacts;
      out.metrics["iris_contacts"] = iris;
      if (r->nucleus) nucleus_removal_metrics(scene, *r->nucleus, out.metrics);
      break;
    }
    case Drill::CornealIncision: {
      uint64_t iris = 0;
      for (const HandRecord& h : r->hands) iris += h.iris_contacts;
      out.metrics["iris_contacts"] = iris;
      incision_metrics(scene, out);  // the wound on the cut cornea (cornea_cutting.hpp)
      break;
    }
  }
  ports_metrics(scene, out.metrics);  // globe rotation, port force (ports on only)
  score(out, scene.drill);
  out.metrics["score"] = out.score;

  for (const DrillEvent& e : r->events) {
    nlohmann::json j = {{"t_s", e.t_s}, {"kind", e.kind}};
    if (e.hand >= 0) {
      const HandRecord& h = r->hands[static_cast<size_t>(e.hand)];
      j["hand"] = std::string(to_string(h.hand));
      j["tool"] = std::string(to_string(h.kind));
    }
    if (e.detail) j[e.detail] = e.value;
    out.events.push_back(std::move(j));
  }
  return out;
}

}  // namespace phaco
