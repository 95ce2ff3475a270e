#include "procedures/scene/run.hpp"

#include <sys/resource.h>

#include <cstdio>
#include <numeric>

#include "engine/core/clock.hpp"
#include "engine/core/version.hpp"
#include "procedures/scene/capsule_cutting.hpp"
#include "procedures/scene/capsule_physics.hpp"
#include "procedures/scene/drill_metrics.hpp"
#include "procedures/scene/lens_fragments.hpp"
#include "procedures/scene/lens_sculpting.hpp"

namespace phaco {

SystemCost cost_of(const SystemTiming& t) {
  SystemCost c{t.name, t.p50_ms(), t.p99_ms(), 0.0, t.percentile_ms(100)};
  if (!t.samples_ms.empty()) {
    c.mean_ms = std::accumulate(t.samples_ms.begin(), t.samples_ms.end(), 0.0) /
                static_cast<double>(t.samples_ms.size());
  }
  return c;
}

double peak_memory_mb() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return static_cast<double>(usage.ru_maxrss) / 1024.0;  // ru_maxrss is in KiB on Linux
}

RunReport run_scenario(const Scenario& scenario, const SceneOptions& options) {
  auto scene = build_scene(scenario, options);
  const uint64_t frames = scenario.frame_count();
  Stopwatch wall;
  for (uint64_t f = 0; f < frames; ++f) step(*scene);
  const double wall_s = wall.elapsed_s();
  RunReport r = report_of(*scene);
  r.wall_time_s = wall_s;
  return r;
}

nlohmann::json systems_json(const std::vector<SystemCost>& systems) {
  nlohmann::json j = nlohmann::json::object();
  for (const SystemCost& s : systems)
    j[s.name] = {
        {"p50_ms", s.p50_ms}, {"p99_ms", s.p99_ms}, {"mean_ms", s.mean_ms}, {"max_ms", s.max_ms}};
  return j;
}

RunReport report_of(Scene& scene) {
  RunReport r;
  r.scenario = scene.scenario.source;
  r.drill = std::string(to_string(scene.scenario.drill));
  r.drill_setup = drill_setup_json(scene);
  r.frames = scene.frame;
  r.sim_time_s = scene.time_s;
  r.threads = scene.executor->threads();
  r.dt_s = scene.scenario.dt_s;
  for (const auto& t : scene.executor->timings()) r.systems.push_back(cost_of(t));
  r.frame = cost_of(scene.executor->frame_timing());
  r.frame.name = "frame";
  r.mesh_load_s = scene.mesh_load_s;
  r.elements = element_counts(scene);
  r.state_hash = state_hash(scene);
  if (auto capsule = capsule_physics_summary(scene); !capsule.is_null())
    r.physics["capsule"] = capsule;
  if (auto cutting = capsule_cutting_summary(scene); !cutting.is_null())
    r.physics["capsule_cutting"] = cutting;
  if (auto lens = lens_sculpting_summary(scene); !lens.is_null())
    r.physics["lens_sculpting"] = lens;
  if (auto lens = lens_fragments_summary(scene); !lens.is_null())
    r.physics["lens_fragments"] = lens;
  DrillReport drill = drill_report(scene);
  r.metrics = std::move(drill.metrics);
  r.targets = std::move(drill.targets);
  r.events = std::move(drill.events);
  r.series = std::move(drill.series);
  r.score_terms = std::move(drill.score_terms);
  r.complications = std::move(drill.complications);
  r.peak_memory_mb = peak_memory_mb();
  return r;
}

nlohmann::json to_json(const RunReport& r) {
  nlohmann::json j;
  j["scenario"] = r.scenario;
  j["drill"] = r.drill;
  j["drill_setup"] = r.drill_setup;
  j["sim_time_s"] = r.sim_time_s;
  j["dt_s"] = r.dt_s;
  j["frames"] = r.frames;
  j["threads"] = r.threads;
  j["systems"] = systems_json(r.systems);
  j["frame"] = {{"p50_ms", r.frame.p50_ms},
                {"p99_ms", r.frame.p99_ms},
                {"mean_ms", r.frame.mean_ms},
                {"max_ms", r.frame.max_ms}};
  j["wall_time_s"] = r.wall_time_s;
  j["mesh_load_s"] = r.mesh_load_s;
  j["peak_memory_mb"] = r.peak_memory_mb;
  nlohmann::json elements = nlohmann::json::object();
  for (const auto& [k, v] : r.elements) elements[k] = v;
  j["elements"] = elements;
  j["metrics"] = r.metrics;
  j["targets"] = r.targets;
  j["events"] = r.events;
  j["series"] = r.series;
  j["score_terms"] = r.score_terms;
  j["physics"] = r.physics;
  j["state_hash"] = r.state_hash;
  // The build that made the run: records and xAPI statements carry it inside the report.
  j["software"] = {{"name", "OpenPhaco"}, {"version", version()}, {"revision", revision()}};
  // A drill that failed (a complication: docs/scoring.md) says so, and why, at the top.
  j["failed"] = !r.complications.empty();
  j["complications"] = r.complications;
  j["attempted"] = r.metrics.value("attempted", 1.0) > 0;
  return j;
}

std::string summary_text(const RunReport& r) {
  std::string out;
  char line[256];
  std::snprintf(line, sizeof line,
                "%s  drill %s  %llu frames (%.3f s simulated at dt %.6f s)  %d thread(s)\n",
                r.scenario.c_str(), r.drill.c_str(), static_cast<unsigned long long>(r.frames),
                r.sim_time_s, r.dt_s, r.threads);
  out += line;
  std::snprintf(line, sizeof line,
                "frame   p50 %.4f ms  p99 %.4f ms   (stepping took %.3f s wall, meshes %.3f s)\n",
                r.frame.p50_ms, r.frame.p99_ms, r.wall_time_s, r.mesh_load_s);
  out += line;
  for (const auto& s : r.systems) {
    std::snprintf(line, sizeof line, "  %-22s p50 %.4f ms  p99 %.4f ms\n", s.name.c_str(), s.p50_ms,
                  s.p99_ms);
    out += line;
  }
  out += "elements:";
  for (const auto& [k, v] : r.elements) out += " " + k + "=" + std::to_string(v);
  for (const auto& [body, ph] : r.physics.items()) {
    if (body == "capsule_cutting") {
      std::snprintf(line, sizeof line,
                    "\ncapsule cutting: %llu cut segments, %llu tear steps (%llu advanced, rule "
                    "%s), %llu run-out "
                    "warnings, %llu radial tear-outs, opening %s",
                    ph.value("cut_segments", 0ull), ph.value("tear_steps", 0ull),
                    ph.value("tear_advances", 0ull),
                    ph.value("tear_rule", std::string("?")).c_str(),
                    ph.value("runout_warnings", 0ull), ph.value("radial_tearouts", 0ull),
                    ph.value("opening_complete", false) ? "closed" : "not closed");
      out += line;
      if (ph.value("opening_complete", false)) {
        std::snprintf(line, sizeof line, " (diameter %.2f mm, circularity %.3f)",
                      ph.value("opening_diameter_mm", 0.0), ph.value("opening_circularity", 0.0));
        out += line;
      }
      continue;
    }
    if (body == "lens_fragments") {
      std::snprintf(line, sizeof line,
                    "\nlens fragments: %llu of %llu cells removed (%.2f mm3), %llu fragment(s) "
                    "now, %llu at most, "
                    "step mean %.3f ms / max %.3f ms",
                    ph.value("cells_removed", 0ull), ph.value("cells", 0ull),
                    ph.value("volume_removed_mm3", 0.0), ph.value("fragments", 0ull),
                    ph.value("max_fragments", 0ull), ph.value("step_ms_mean", 0.0),
                    ph.value("step_ms_max", 0.0));
      out += line;
      continue;
    }
    if (body == "lens_sculpting") {
      std::snprintf(line, sizeof line,
                    "\nlens sculpting: %llu tets removed (%.2f mm3) in %llu strokes, ultrasound "
                    "%.2f s, sculpt step "
                    "mean %.3f ms / max %.3f ms, nucleus turned %.1f deg, %llu trench(es)",
                    ph.value("tets_removed", 0ull), ph.value("volume_removed_mm3", 0.0),
                    ph.value("strokes", 0ull), ph.value("ultrasound_time_s", 0.0),
                    ph.value("sculpt_ms_mean", 0.0), ph.value("sculpt_ms_max", 0.0),
                    ph.value("nucleus_rotation_deg", 0.0), ph.value("trench_count", 0ull));
      out += line;
      for (const auto& t : ph.value("trenches", nlohmann::json::array())) {
        std::snprintf(
            line, sizeof line,
            "\n  trench: width %.2f mm, depth %.2f mm (%.0f %% of the nucleus), axis %.0f deg",
            t.value("width_mm", 0.0), t.value("depth_mm", 0.0),
            100.0 * t.value("depth_fraction", 0.0), t.value("axis_deg", 0.0));
        out += line;
      }
      if (ph.value("trench_count", 0ull) >= 2) {
        std::snprintf(line, sizeof line, "\n  trenches cross at %.1f deg",
                      ph.value("trench_crossing_angle_deg", 0.0));
        out += line;
      }
      continue;
    }
    out += "\n" + body + ": " + ph.value("integrator", std::string("?")) + ", active set mean " +
           std::to_string(static_cast<long long>(ph.value("active_particles_mean", 0.0))) +
           " / max " + std::to_string(ph.value("active_particles_max", 0u)) + " particles, " +
           std::to_string(ph.value("frames_stepped", 0ull)) + " frames stepped, " +
           std::to_string(ph.value("divergences", 0ull)) + " divergences, " +
           std::to_string(ph.value("grasps", 0ull)) + " grasps";
  }
  if (r.metrics.contains("score")) {
    std::snprintf(line, sizeof line, "\nscore %.1f / 100", r.metrics["score"].get<double>());
    out += line;
    if (r.metrics.value("attempted", 1.0) <= 0) out += "   NOT ATTEMPTED (scores 0)";
    for (const auto& c : r.complications) {
      std::snprintf(line, sizeof line, "   FAILED (%s: score capped at %.0f)",
                    c.value("name", std::string()).c_str(), c.value("score_cap", 0.0));
      out += line;
    }
    for (const auto& t : r.score_terms) {
      const std::string value = t["value"].is_number() ? t["value"].dump() : std::string("-");
      std::snprintf(line, sizeof line, "\n  %-28s %-12s %5.1f / %4.1f",
                    t.value("metric", std::string()).c_str(), value.c_str(), t.value("points", 0.0),
                    t.value("weight", 0.0));
      out += line;
    }
  }
  if (!r.metrics.empty()) out += "\nmetrics:";
  for (const auto& [name, value] : r.metrics.items()) {
    std::string target;
    if (r.targets.contains(name)) {
      const auto& b = r.targets[name];
      target = "  target " + (b.contains("min") ? b["min"].dump() : std::string()) + ".." +
               (b.contains("max") ? b["max"].dump() : std::string());
    }
    std::snprintf(line, sizeof line, "\n  %-32s %.4g%s", name.c_str(),
                  value.is_number() ? value.get<double>() : 0.0, target.c_str());
    out += line;
  }
  std::snprintf(line, sizeof line,
                "\npeak memory %.1f MiB   metrics %zu   events %zu   state hash %s\n",
                r.peak_memory_mb, r.metrics.size(), r.events.size(), r.state_hash.c_str());
  out += line;
  return out;
}

}  // namespace phaco
