#pragma once
// The 1 kHz haptic thread (issue 6 item 1; seed 003 §III.C: force feedback at 1000 Hz against a
// mesh updated far slower; DESIGN.md §5).
//
// One thread ticks a caller's function on absolute deadlines, deadline_k = start + k·period, so
// errors never accumulate (a relative sleep of one period drifts by every wake-up's lateness).
// Each wait sleeps with clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME) until a margin before the
// deadline, then spins on the clock to it: the sleep gives the core back, the spin absorbs the
// kernel's wake-up latency. The margin follows that latency as the loop observes it, between
// spin_ns and max_spin_ns (spin_margin.hpp): it grows when the cores are loaded. The thread asks
// for SCHED_FIFO and locked memory and reports what it actually got (RealtimeStatus); without them
// the loop still runs, with worse figures.
//
// A tick that wakes after the following deadline has passed is an overrun: the tick still runs
// at once (the device needs a force), the deadlines already past are counted as missed and the
// loop aims at the next future deadline rather than running a burst of catch-up ticks. So a
// tick's index is its deadline's k and indices skip after an overrun.
//
// Hot path: after start-up the loop thread calls only the clock, clock_nanosleep and the tick
// function; it neither allocates, locks nor throws (tests/engine/haptics counts allocations).
// Clock: CLOCK_MONOTONIC, the clock behind std::chrono::steady_clock on Linux and so the one of
// engine/core/clock.hpp now_ns(); TickInfo times compare directly with now_ns().
#include <atomic>
#include <cstdint>
#include <string>
#include <thread>

#include "engine/haptics/loop_stats.hpp"

namespace phaco {

struct LoopSettings {
  int64_t period_ns = 1'000'000;  // 1 kHz
  int64_t spin_ns =
      60'000;  // sleep to deadline − margin, then spin; 0 = sleep only, ≥ period = spin only
  int64_t max_spin_ns = 250'000;  // the margin grows with the observed wake-up latency up to
                                  // this (spin_margin.hpp); ≤ spin_ns: a fixed margin of spin_ns
  // The margin the first sleep uses, kept within [spin_ns, max_spin_ns]; 0: spin_ns. A loop that
  // follows another on the same machine (the trainer's next procedure step: a new session, a new
  // loop) starts from the previous loop's learned spin_margin_ns() instead of the floor, so it
  // need not be late once to relearn a load that has not changed (docs/haptic_loop.md).
  int64_t start_margin_ns = 0;
  bool realtime = true;        // ask for SCHED_FIFO
  int priority = 80;           // SCHED_FIFO priority, 1–99
  bool lock_memory = true;     // mlockall(MCL_CURRENT | MCL_FUTURE): no page faults on the hot path
  int cpu = -1;                // pin the thread to this CPU if ≥ 0
  int64_t warmup_ticks = 200;  // first ticks run but are not counted in the statistics
};

// What the loop thread asked for and what it got, as the thread itself saw it.
struct RealtimeStatus {
  bool requested = false;      // settings.realtime
  bool fifo = false;           // the thread runs under SCHED_FIFO (read back, not assumed)
  bool memory_locked = false;  // mlockall succeeded
  bool pinned = false;         // pinned to settings.cpu
  int priority = 0;            // the thread's scheduling priority as read back
  std::string detail;          // why not, e.g. "SCHED_FIFO refused: Operation not permitted (...)"
};

struct TickInfo {
  int64_t index = 0;        // k: deadline_ns = start_ns + k·period_ns exactly
  int64_t deadline_ns = 0;  // CLOCK_MONOTONIC
  int64_t wake_ns = 0;      // when the tick began, ≥ deadline_ns
};

// A plain function pointer and a context: no std::function, nothing to allocate.
using TickFn = void (*)(void* context, const TickInfo&);

// Thread-safety (issue 22), on every public method as "Thread:": one owner thread starts and
// stops the loop; the tick function runs on the loop thread only.
class HapticLoop {
 public:
  HapticLoop() = default;
  ~HapticLoop();  // stops
  HapticLoop(const HapticLoop&) = delete;
  HapticLoop& operator=(const HapticLoop&) = delete;

  // Starts the thread and returns once it has set itself up (priority, memory lock, stack) and
  // reported its RealtimeStatus; the first tick follows one period later. Throws
  // std::invalid_argument for bad settings, std::logic_error if already running,
  // std::system_error if the thread cannot be created. Thread: the owner.
  void start(TickFn tick, void* context, const LoopSettings& settings);
  // Asks the thread to stop after its current tick and joins it. Idempotent. Thread: the owner,
  // never the tick function (it would join itself).
  void stop();
  // Thread: the owner.
  bool running() const { return thread_.joinable(); }

  // Valid after start() returned (and after stop()). Thread: the owner (the loop thread writes
  // them only before start() returns).
  RealtimeStatus realtime_status() const { return status_; }
  int64_t start_ns() const { return start_ns_; }  // deadline of tick 0
  const LoopSettings& settings() const { return settings_; }
  // The spin margin the loop's next sleep uses (spin_margin.hpp), what it has learned of the
  // wake-up latency: settings().start_margin_ns (clamped) once start() returned, then updated
  // every tick, and kept after stop(), so a following loop can start from it
  // (LoopSettings::start_margin_ns). Thread: any (relaxed: a figure).
  int64_t spin_margin_ns() const { return spin_margin_ns_.load(std::memory_order_relaxed); }
  // Any thread, also while running (approximate then; see loop_stats.hpp).
  LoopStatsSnapshot stats() const { return stats_.snapshot(); }
  // The period's histogram bins (charts of the period under load). Thread: any, as stats().
  std::vector<DurationHistogram::Bin> period_bins() const {
    return stats_.period().occupied_bins();
  }
  // The period's histogram itself, to pool it with other loops' (DurationHistogram::merge).
  // Thread: any, as stats(); valid while this loop lives.
  const DurationHistogram& period_histogram() const { return stats_.period(); }

 private:
  void run();
  void set_up_thread();

  TickFn tick_ = nullptr;
  void* context_ = nullptr;
  LoopSettings settings_;
  RealtimeStatus status_;
  int64_t start_ns_ = 0;
  LoopStats stats_;
  std::atomic<bool> stop_{false};
  std::atomic<bool> ready_{false};
  std::atomic<int64_t> spin_margin_ns_{0};
  std::thread thread_;
};

}  // namespace phaco
