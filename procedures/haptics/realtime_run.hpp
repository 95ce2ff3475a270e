#pragma once
// A scene stepped in real time next to a haptic session: frame k starts at start + k·dt on the
// wall clock (the simulation sleeps when early, runs on when late, never catches up in a burst),
// device-driven hands follow their devices, and every frame publishes the local haptic model.
// What `phaco run --haptics`, the trainer and the perf harness's haptics study run.
//
// A stall can be injected (the simulation thread sleeps `stall_ms` at `stall_at_s` instead of
// stepping) to show that the haptic thread keeps the force continuous without new models.
#include <atomic>
#include <cstdint>
#include <functional>
#include <nlohmann/json.hpp>

#include "procedures/haptics/haptic_session.hpp"
#include "procedures/scene/run.hpp"
#include "procedures/scene/scene.hpp"

namespace phaco {

struct RealtimeRunOptions {
  double duration_s = 0;   // wall seconds to run; 0 = the scenario's duration
  double stall_at_s = -1;  // < 0: no stall
  double stall_ms = 0;
  // The scene is rebuilt and restarted when its scenario ends before duration_s (the harness
  // runs a 60 s measurement on a 40 s scenario).
  bool loop_scenario = true;
  // The trainer's hooks (procedures/trainer), all on the simulation thread; empty/null: unused.
  std::function<void(Scene&)> after_frame;  // after every step (and the one before the start)
  std::function<void(Scene&)> at_end;       // once, after the last frame, the session stopped
  const std::atomic<bool>* stop = nullptr;  // set: the run ends before its next frame
  // Set: no steps (the haptic thread runs on); on resume the frame clock restarts from now, so
  // the paused time is neither simulated nor caught up.
  const std::atomic<bool>* pause = nullptr;
};

struct RealtimeRunReport {
  uint64_t frames = 0;
  double wall_s = 0;
  double frame_p50_ms = 0, frame_p99_ms = 0, frame_max_ms = 0;  // one step's cost
  uint64_t late_frames = 0;  // started more than one dt after their deadline
  double max_lag_ms = 0;     // the latest a frame started after its deadline
  uint32_t restarts = 0;     // scenario restarted (loop_scenario)
  // Each system's cost over the last scene's frames (a restart begins a new scene): where a
  // frame's time goes with the haptic thread beside the simulation.
  std::vector<SystemCost> systems;
  HapticSessionStats haptics;
};

// Builds the scene with `session` as its haptic port, starts the session, runs, stops it.
// Throws InputError for a bad scenario (as build_scene does).
RealtimeRunReport run_realtime(const Scenario& scenario, SceneOptions options,
                               HapticSession& session, const RealtimeRunOptions& run);

nlohmann::json to_json(const HapticSessionStats& stats);
nlohmann::json to_json(const RealtimeRunReport& report);
std::string summary_text(const RealtimeRunReport& report);

}  // namespace phaco
