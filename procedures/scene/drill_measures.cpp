// The drill's measures at its end; see drill_measures.hpp.
#include "procedures/scene/drill_measures.hpp"

#include <algorithm>
#include <cmath>
#include <span>
#include <string>
#include <string_view>

#include "components/particles.hpp"
#include "components/triangles.hpp"
#include "procedures/rhexis/opening.hpp"
#include "procedures/scene/capsule_cutting.hpp"
#include "procedures/scene/capsule_physics.hpp"
#include "procedures/scene/lens_sculpting.hpp"
#include "procedures/scene/scene.hpp"

namespace phaco {

namespace {

constexpr uint32_t kHistogramBins = 20;

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

}  // namespace

void hand_metrics(const DrillRecord& r, DrillReport& out, const std::vector<size_t>& idx) {
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

}  // namespace phaco
