// The drill's report at its end (drill_metrics.hpp): the record's measures, the drill's own
// (drill_measures, the incision's, the nucleus removal's, the ports'), the score and the events.
// The record is kept by drill_events.cpp.
#include "procedures/scene/drill_metrics.hpp"

#include <string>

#include "procedures/scene/cornea_cutting.hpp"
#include "procedures/scene/drill_measures.hpp"
#include "procedures/scene/drill_record.hpp"
#include "procedures/scene/drill_score.hpp"
#include "procedures/scene/nucleus_removal_metrics.hpp"
#include "procedures/scene/rim_tear.hpp"
#include "procedures/scene/scene.hpp"
#include "procedures/scene/tool_ports.hpp"

namespace phaco {

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
  hand_metrics(*r, out, idx);

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
  rim_metrics(scene, out.metrics);    // tools pressing the rhexis rim (an opening only)
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
