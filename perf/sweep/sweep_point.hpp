#pragma once
// One point of the issue-9 sweep: a drill's scripted expert run to its end at one resolution
// level, thread count and method choice, with the 1 kHz haptic thread ticking beside it, in a
// process of its own (so peak memory is the point's, and a point that crashes is reported, not
// fatal to the sweep).
//
// Recorded: frame time p50/p99/max/mean and the same per system; the haptic period's summary,
// overruns, allocations on the haptic thread and histogram while the frames run; resident memory
// before the scene, after building it and at its peak while stepping, and bytes per element; the
// drill's metrics (for accuracy against the reference point, perf/study_sweep.cpp), the physics
// summaries, the state hash that ties the figures to a reproducible run, and the round trip
// between the two CPUs before and after the frames.
#include <array>
#include <cstdint>
#include <filesystem>
#include <limits>
#include <map>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace phaco::perf {

struct SweepPointConfig {
  std::string drill;                           // capsulorhexis, phaco_sculpting, corneal_incision
  std::filesystem::path scenario;              // the drill's scripted expert
  int level = 3;                               // eye resolution level
  int threads = 1;                             // simulation threads (oneTBB)
  std::string capsule_layout;                  // "" = the scenario's (curvilinear)
  std::map<std::string, std::string> methods;  // added to the scenario's "methods"
  std::string variant = "default";             // label: "default" or "key=value"
  int dt_divisor = 1;                          // run at the scenario's dt_s / dt_divisor, same
                                               // tracks (the converged reference's smaller step)
  bool haptics = true;                         // the 1 kHz thread beside the frames
  bool graph_every_frame = false;              // Dispatch::Graph instead of Auto (executor.hpp)
  bool realtime = true;                        // ask SCHED_FIFO for it (mlockall is not asked:
                                               // it would count untouched mappings as resident)
  bool warm_only = false;                      // build the scene (fills the mesh cache), no steps
  std::filesystem::path cache_dir;             // mesh cache
};

struct CostSummary {
  std::string name;
  double p50_ms = 0, p99_ms = 0, max_ms = 0, mean_ms = 0;
};

struct SweepPointResult {
  SweepPointConfig config;
  bool ok = false;
  std::string error;  // why the point failed (input error, crash, exit status)
  uint64_t frames = 0;
  double sim_s = 0, wall_s = 0, mesh_load_s = 0;
  CostSummary frame;
  std::vector<CostSummary> systems;
  // Frames the executor sent through the flow graph and ran serially (Dispatch::Auto's choice).
  uint64_t graph_frames = 0, serial_frames = 0;
  // Haptic thread while the frames ran.
  bool haptic_fifo = false;
  std::string haptic_detail;
  double haptic_ticks = 0, haptic_overruns = 0, haptic_missed = 0;
  double period_p50_us = 0, period_p99_us = 0, period_p999_us = 0, period_max_us = 0;
  // The wait's spin before each deadline and the tick's own compute (its CPU share beside the
  // frames: what the simulation threads lose to it), µs.
  double spin_mean_us = 0, spin_p50_us = 0, spin_p99_us = 0;
  double compute_mean_us = 0, compute_p50_us = 0, compute_p99_us = 0;
  double haptic_allocations = -1;                  // −1: not countable (sanitizer build)
  std::vector<std::array<double, 3>> period_bins;  // (low µs, width µs, count)
  // Memory (MiB, resident): before the scene, after building it, peak while stepping.
  double rss_before_mb = 0, rss_scene_mb = 0, rss_peak_mb = 0;
  std::map<std::string, uint64_t> elements;
  uint64_t total_elements = 0;   // particles + triangles + tets of every body
  double bytes_per_element = 0;  // (peak − before) / total_elements
  nlohmann::json metrics = nlohmann::json::object();
  nlohmann::json physics = nlohmann::json::object();
  std::string state_hash;
  // A cache line's round trip between the process's two CPUs just before the frames and just after
  // them (perf/cores.hpp), ns; NaN on one CPU or in points saved before it was recorded. Where the
  // host puts its vCPUs decides whether a team of two threads pays (docs/perf_sweep.md).
  double round_trip_before_ns = std::numeric_limits<double>::quiet_NaN();
  double round_trip_after_ns = std::numeric_limits<double>::quiet_NaN();
};

// Runs the point in this process (what the child does).
SweepPointResult run_sweep_point(const SweepPointConfig& config);

// Runs the point in a child process: `exe _sweep-point IN OUT`, files in work_dir. A child that
// fails or crashes gives ok = false with the reason (its exit status and last stderr line).
SweepPointResult run_sweep_point_isolated(const SweepPointConfig& config,
                                          const std::filesystem::path& exe,
                                          const std::filesystem::path& work_dir);

// The child's entry point: args = {IN, OUT}. Returns the process exit code.
int sweep_point_main(const std::vector<std::string>& args);

nlohmann::json to_json(const SweepPointConfig& c);
SweepPointConfig config_from_json(const nlohmann::json& j);
nlohmann::json to_json(const SweepPointResult& r);
SweepPointResult result_from_json(const nlohmann::json& j);

}  // namespace phaco::perf
