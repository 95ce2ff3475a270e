#pragma once
// Runs a scenario headless for its duration at the fixed step and collects the report of
// issue 2 / DESIGN.md §7: what ran, how long each system took, how big the scene was, and the
// state hash that ties the figures to a reproducible run.
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "procedures/scene/scene.hpp"

namespace phaco {

struct SystemCost {
  std::string name;
  double p50_ms = 0, p99_ms = 0, mean_ms = 0, max_ms = 0;
};

struct RunReport {
  std::string scenario;  // file
  std::string drill;
  // The drill file and the patient settings the difficulty resolved to (docs/drills.md).
  nlohmann::json drill_setup = nlohmann::json::object();
  double sim_time_s = 0;
  uint64_t frames = 0;
  int threads = 1;
  double dt_s = 0;
  std::vector<SystemCost> systems;
  SystemCost frame;        // the whole frame
  double wall_time_s = 0;  // stepping only
  double mesh_load_s = 0;  // meshes loaded from the cache or generated
  double peak_memory_mb = 0;
  std::vector<std::pair<std::string, uint64_t>> elements;
  // Issue 7 item 3 (procedures/scene/drill_metrics.hpp, docs/metrics.md, docs/scoring.md).
  nlohmann::json metrics = nlohmann::json::object();  // name (units in it) → number, with "score"
  nlohmann::json targets = nlohmann::json::object();  // name → {"min": a, "max": b}
  nlohmann::json events = nlohmann::json::array();    // {"t_s", "kind", "hand"?, ...} by time
  nlohmann::json series = nlohmann::json::object();  // t_s, hands, rhexis, trench (≤ 2000 samples)
  // The score's breakdown: {"metric", "value", "target", "weight", "points"} per term.
  nlohmann::json score_terms = nlohmann::json::array();
  // The complications that failed the drill and capped its score: {"name", "metric", "value",
  // "score_cap"} (docs/scoring.md); metrics.attempted 0 says the step was not attempted (score 0).
  nlohmann::json complications = nlohmann::json::array();
  // Per deformable body: method, steps, divergences, active set.
  nlohmann::json physics = nlohmann::json::object();
  std::string state_hash;
};

RunReport run_scenario(const Scenario& scenario, const SceneOptions& options);
// The report of a scene as it stands (run_scenario's, after its last step; the trainer's live
// scene at its end): what ran, each system's cost, the sizes, the drill's metrics, the physics
// summaries and the state hash. wall_time_s is left 0: only the caller knows what it timed.
RunReport report_of(Scene& scene);

// One system's (or the frame's) cost over the frames its executor has timed.
SystemCost cost_of(const SystemTiming& timing);
// {name: {p50_ms, p99_ms, mean_ms, max_ms}}, the report's "systems".
nlohmann::json systems_json(const std::vector<SystemCost>& systems);
nlohmann::json to_json(const RunReport& report);
std::string summary_text(const RunReport& report);
// Peak resident set size of this process so far, MiB.
double peak_memory_mb();

}  // namespace phaco
