#include "perf/haptics/loop_measure.hpp"

#include <chrono>
#include <cmath>
#include <thread>

#include "engine/core/clock.hpp"
#include "perf/cores.hpp"

namespace phaco::perf {

namespace {

// The stand-in force computation: spin on the clock for work_ns.
void busy_tick(void* context, const TickInfo& info) {
  const int64_t work_ns = *static_cast<const int64_t*>(context);
  const int64_t until = info.wake_ns + work_ns;
  while (now_ns() < until) {
  }
}

void busy_load(const std::atomic<bool>& stop) {
  volatile double x = 1.0;
  // Relaxed: a stop request, no data.
  while (!stop.load(std::memory_order_relaxed))
    for (int i = 0; i < 10'000; ++i) x = std::sqrt(x + 1.0);
}

}  // namespace

const char* loop_load_name(LoopLoad load) {
  switch (load) {
    case LoopLoad::None:
      return "none";
    case LoopLoad::BusyOtherCore:
      return "busy other core";
    case LoopLoad::Background:
      return "background";
  }
  return "?";
}

std::vector<LoopMeasureCase> default_loop_cases(double seconds, int64_t work_ns) {
  std::vector<LoopMeasureCase> cases;
  // The wait's margin: fixed at 60 us, following the wake-up latency from 60 up to 250 us (the
  // default, engine/haptics/spin_margin.hpp), or none.
  struct Wait {
    int64_t spin_ns, max_spin_ns;
    const char* label;
  };
  for (bool realtime : {true, false})
    for (const Wait w :
         {Wait{60'000, 60'000, ", sleep + 60 us spin"},
          Wait{60'000, 250'000, ", sleep + 60-250 us adaptive spin"}, Wait{0, 0, ", sleep only"}}) {
      LoopMeasureCase c;
      c.label = std::string(realtime ? "SCHED_FIFO" : "normal") + w.label;
      c.settings.realtime = realtime;
      c.settings.spin_ns = w.spin_ns;
      c.settings.max_spin_ns = w.max_spin_ns;
      c.settings.cpu = 0;
      c.seconds = seconds;
      c.work_ns = work_ns;
      c.load = LoopLoad::BusyOtherCore;
      c.load_cpu = 1;
      cases.push_back(std::move(c));
    }
  return cases;
}

LoopMeasureRow measure_loop(const LoopMeasureCase& c) {
  std::atomic<bool> stop_load{false};
  std::thread load;
  if (c.load != LoopLoad::None) {
    load = std::thread([&] {
      const PinnedScope pin(c.load_cpu);  // best effort: a load is a load
      if (c.load == LoopLoad::Background && c.background)
        c.background(stop_load);
      else
        busy_load(stop_load);
    });
  }

  int64_t work_ns = c.work_ns;
  HapticLoop loop;
  const auto warmup = std::chrono::nanoseconds(c.settings.warmup_ticks * c.settings.period_ns);
  const int64_t t0 = now_ns();
  loop.start(c.tick ? c.tick : &busy_tick, c.tick ? c.tick_context : &work_ns, c.settings);
  std::this_thread::sleep_for(warmup + std::chrono::duration<double>(c.seconds));
  loop.stop();
  const int64_t t1 = now_ns();

  // Relaxed: a stop request; the join synchronises.
  stop_load.store(true, std::memory_order_relaxed);
  if (load.joinable()) load.join();

  LoopMeasureRow row;
  row.label = c.label;
  row.settings = c.settings;
  row.seconds = static_cast<double>(t1 - t0) * 1e-9 - std::chrono::duration<double>(warmup).count();
  row.work_ns = c.tick ? 0 : c.work_ns;
  row.load = c.load;
  row.status = loop.realtime_status();
  row.stats = loop.stats();
  return row;
}

std::vector<LoopMeasureRow> measure_loop(const std::vector<LoopMeasureCase>& cases) {
  std::vector<LoopMeasureRow> rows;
  rows.reserve(cases.size());
  for (const LoopMeasureCase& c : cases) rows.push_back(measure_loop(c));
  return rows;
}

}  // namespace phaco::perf
