#pragma once
// Measurement of the 1 kHz haptic loop (engine/haptics/haptic_loop.hpp) for the `phaco-perf
// haptics` study (issue 6, "Rates"): runs the loop for a while with given settings, optionally
// with a load on the other core, and returns the period, wake-up lateness and compute-time
// statistics with the real-time status the thread actually got. Rows only; the harness prints,
// charts and compares them with the targets (p99 ≤ 1.02 ms, max ≤ 1.5 ms, lateness p99 ≤ 20 µs).
//
// The tick does `work_ns` of busy work on the clock (a stand-in for the force computation) unless
// the caller gives its own tick. The load is either a busy thread (arithmetic, no memory traffic)
// or a caller's function, e.g. the simulation running the capsulorhexis scene, run in its own
// thread until told to stop; both pinned to `load_cpu` when ≥ 0.
#include <atomic>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "engine/haptics/haptic_loop.hpp"

namespace phaco::perf {

enum class LoopLoad : uint8_t { None, BusyOtherCore, Background };

struct LoopMeasureCase {
  std::string label;
  LoopSettings settings;
  double seconds = 5.0;      // s, after warm-up
  int64_t work_ns = 50'000;  // busy work per tick when `tick` is null
  TickFn tick = nullptr;     // optional: the caller's tick instead of the busy work
  void* tick_context = nullptr;
  LoopLoad load = LoopLoad::None;
  int load_cpu = 1;  // pin the load thread here if ≥ 0
  // LoopLoad::Background: runs in the load thread and must return soon after `stop` turns true.
  std::function<void(const std::atomic<bool>& stop)> background;
};

struct LoopMeasureRow {
  std::string label;
  LoopSettings settings;
  double seconds = 0;   // s, measured wall time the loop ran
  int64_t work_ns = 0;  // 0 when the caller's tick was used
  LoopLoad load = LoopLoad::None;
  RealtimeStatus status;    // what the loop thread got
  LoopStatsSnapshot stats;  // period, lateness, compute (µs), overruns
};

// Realtime on and off, each with sleep + a fixed 60 µs spin, sleep + the adaptive 60–250 µs spin
// (the default) and sleep only, all with a busy load on the other core, pinned apart.
std::vector<LoopMeasureCase> default_loop_cases(double seconds, int64_t work_ns = 50'000);

LoopMeasureRow measure_loop(const LoopMeasureCase& c);
std::vector<LoopMeasureRow> measure_loop(const std::vector<LoopMeasureCase>& cases);

const char* loop_load_name(LoopLoad load);

}  // namespace phaco::perf
