#include "procedures/haptics/realtime_run.hpp"

#include <time.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <vector>

#include "engine/core/clock.hpp"
#include "engine/schedule/executor.hpp"
#include "procedures/scene/run.hpp"

namespace phaco {
namespace {

void sleep_until_ns(int64_t deadline_ns) {
  timespec ts{static_cast<time_t>(deadline_ns / 1'000'000'000),
              static_cast<long>(deadline_ns % 1'000'000'000)};
  while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &ts, nullptr) != 0) {
  }
}

double percentile(std::vector<double>& v, double q) {
  if (v.empty()) return 0;
  const size_t k =
      std::min(v.size() - 1, static_cast<size_t>(q * static_cast<double>(v.size() - 1) + 0.5));
  std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(k), v.end());
  return v[k];
}

nlohmann::json summary_json(const DurationSummary& d) {
  return {{"count", d.count},   {"mean_us", d.mean_us}, {"p50_us", d.p50_us},
          {"p99_us", d.p99_us}, {"p999_us", d.p999_us}, {"max_us", d.max_us}};
}

std::string line(const char* name, const DurationSummary& d) {
  char buf[200];
  std::snprintf(buf, sizeof buf, "  %-9s p50 %8.1f  p99 %8.1f  p99.9 %8.1f  max %8.1f us\n", name,
                d.p50_us, d.p99_us, d.p999_us, d.max_us);
  return buf;
}

}  // namespace

RealtimeRunReport run_realtime(const Scenario& scenario, SceneOptions options,
                               HapticSession& session, const RealtimeRunOptions& run) {
  options.haptics = &session;
  auto scene = build_scene(scenario, options);
  const double dt = scenario.dt_s;
  const double duration = run.duration_s > 0 ? run.duration_s : scenario.duration_s;
  const auto frames_total = static_cast<uint64_t>(std::ceil(duration / dt - 1e-9));
  const auto scenario_frames = scenario.frame_count();

  RealtimeRunReport report;
  std::vector<double> costs;
  costs.reserve(std::min<uint64_t>(frames_total, uint64_t{1} << 20));
  // The first model before the thread starts, so the first tick already has the scene.
  step(*scene);
  if (run.after_frame) run.after_frame(*scene);
  session.start();
  const int64_t start = now_ns();
  int64_t paused_ns = 0;  // wall time spent paused: the frame clock is shifted by it
  const auto dt_ns = static_cast<int64_t>(std::llround(dt * 1e9));
  bool stalled = false;
  // The step before the start is one frame more than the run's: a run as long as its scenario
  // steps its last frame on the first scene (tools holding their last pose), rather than rebuild
  // the scene for that one frame and report on a scene one frame old.
  uint64_t frames_beyond_scenario = 1;
  for (uint64_t k = 0; k < frames_total; ++k) {
    if (run.stop && run.stop->load(std::memory_order_acquire)) break;
    if (run.pause && run.pause->load(std::memory_order_acquire)) {
      const int64_t paused_at = now_ns();
      while (run.pause->load(std::memory_order_acquire) &&
             !(run.stop && run.stop->load(std::memory_order_acquire))) {
        sleep_until_ns(now_ns() + 2'000'000);  // a UI's pause: 2 ms polling is plenty
      }
      paused_ns += now_ns() - paused_at;
      --k;  // the frame was not stepped: check stop, then step it
      continue;
    }
    const int64_t deadline = start + paused_ns + static_cast<int64_t>(k) * dt_ns;
    int64_t now = now_ns();
    if (now < deadline) {
      sleep_until_ns(deadline);
      now = now_ns();
    }
    const double lag_ms = static_cast<double>(now - deadline) * 1e-6;
    report.max_lag_ms = std::max(report.max_lag_ms, lag_ms);
    if (now - deadline > dt_ns) ++report.late_frames;
    if (!stalled && run.stall_at_s >= 0 && static_cast<double>(k) * dt >= run.stall_at_s) {
      stalled = true;  // the simulation hangs: no step, no model, while the haptic thread goes on
      sleep_until_ns(now_ns() + static_cast<int64_t>(run.stall_ms * 1e6));
      continue;
    }
    if (run.loop_scenario && scene->frame >= scenario_frames + frames_beyond_scenario) {
      scene = build_scene(scenario, options);  // a long measurement on a short scenario
      frames_beyond_scenario = 0;
      ++report.restarts;
    }
    Stopwatch cost;
    step(*scene);
    costs.push_back(cost.elapsed_ms());
    ++report.frames;
    if (run.after_frame) run.after_frame(*scene);
  }
  report.wall_s = static_cast<double>(now_ns() - start - paused_ns) * 1e-9;
  const HapticSessionStats running = session.stats();  // the devices' health while they ran
  session.stop();
  report.haptics = session.stats();
  for (size_t k = 0; k < kHapticTools; ++k)
    report.haptics.hands[k].health = running.hands[k].health;
  report.frame_max_ms = costs.empty() ? 0 : *std::max_element(costs.begin(), costs.end());
  report.frame_p99_ms = percentile(costs, 0.99);
  report.frame_p50_ms = percentile(costs, 0.50);
  for (const SystemTiming& t : scene->executor->timings()) report.systems.push_back(cost_of(t));
  if (run.at_end) run.at_end(*scene);
  return report;
}

nlohmann::json to_json(const HapticSessionStats& s) {
  nlohmann::json hands = nlohmann::json::object();
  for (size_t k = 0; k < s.hands.size(); ++k) {
    const HapticHandStats& h = s.hands[k];
    if (!h.attached) continue;
    const DeviceCounters& c = h.counters;
    hands[std::string(to_string(static_cast<Hand>(k)))] = {
        {"health", std::string(to_string(h.health))},
        {"ticks", h.ticks},
        {"samples", h.samples},
        {"samples_dropped", h.samples_dropped},
        {"samples_out_of_bounds",
         {{"non_finite", h.samples_non_finite},
          {"outside_workspace", h.samples_outside_workspace},
          {"clamped", h.samples_clamped}}},
        {"zero_force_ticks", h.zero_force_ticks},
        {"models_adopted", h.models_adopted},
        {"clamped_ticks", h.clamped_ticks},
        {"rejected_inputs", h.rejected_inputs},
        {"max_force_mn", h.max_force_mn},
        {"max_force_step_mn", h.max_force_step_mn},
        {"latency", summary_json(h.latency)},
        {"packets",
         {{"accepted", c.accepted},
          {"malformed", c.malformed},
          {"bad_checksum", c.bad_checksum},
          {"wrong_version", c.wrong_version},
          {"wrong_peer", c.wrong_peer},
          {"non_finite", c.non_finite},
          {"out_of_workspace", c.out_of_workspace},
          {"duplicate", c.duplicate},
          {"out_of_order", c.out_of_order},
          {"stale", c.stale},
          {"clamped", c.clamped},
          {"silences", c.silences}}}};
  }
  return {{"realtime",
           {{"requested", s.realtime.requested},
            {"fifo", s.realtime.fifo},
            {"memory_locked", s.realtime.memory_locked},
            {"priority", s.realtime.priority},
            {"detail", s.realtime.detail}}},
          {"ticks", s.loop.ticks},
          {"overruns", s.loop.overruns},
          {"missed_deadlines", s.loop.missed_deadlines},
          {"period", summary_json(s.loop.period)},
          {"lateness", summary_json(s.loop.lateness)},
          {"compute", summary_json(s.loop.compute)},
          {"spin", summary_json(s.loop.spin)},
          {"models_published", s.models_published},
          {"hands", hands}};
}

nlohmann::json to_json(const RealtimeRunReport& r) {
  return {{"frames", r.frames},
          {"wall_s", r.wall_s},
          {"frame_p50_ms", r.frame_p50_ms},
          {"frame_p99_ms", r.frame_p99_ms},
          {"frame_max_ms", r.frame_max_ms},
          {"late_frames", r.late_frames},
          {"max_lag_ms", r.max_lag_ms},
          {"restarts", r.restarts},
          {"systems", systems_json(r.systems)},
          {"haptics", to_json(r.haptics)}};
}

std::string summary_text(const RealtimeRunReport& r) {
  std::string out;
  char buf[400];
  std::snprintf(
      buf, sizeof buf,
      "real time: %llu frames in %.2f s; step p50 %.2f ms, p99 %.2f ms, max %.2f ms; %llu late "
      "(max lag %.1f ms)\n",
      static_cast<unsigned long long>(r.frames), r.wall_s, r.frame_p50_ms, r.frame_p99_ms,
      r.frame_max_ms, static_cast<unsigned long long>(r.late_frames), r.max_lag_ms);
  out += buf;
  const HapticSessionStats& s = r.haptics;
  std::snprintf(buf, sizeof buf, "haptic thread: %s%s; %lld ticks, %lld overruns, %llu models\n",
                s.realtime.fifo ? "SCHED_FIFO" : "normal priority",
                s.realtime.detail.empty() ? "" : (" (" + s.realtime.detail + ")").c_str(),
                static_cast<long long>(s.loop.ticks), static_cast<long long>(s.loop.overruns),
                static_cast<unsigned long long>(s.models_published));
  out += buf;
  if (s.realtime.requested && !s.realtime.fifo) {
    out +=
        "WARNING: no real-time priority: the 1 kHz haptic loop may be late by milliseconds under "
        "load\n";
  }
  out += line("period", s.loop.period);
  out += line("lateness", s.loop.lateness);
  out += line("compute", s.loop.compute);
  out += line("spin", s.loop.spin);
  for (size_t k = 0; k < s.hands.size(); ++k) {
    const HapticHandStats& h = s.hands[k];
    if (!h.attached) continue;
    std::snprintf(
        buf, sizeof buf,
        "%s hand: %s; %llu samples, %llu zero-force ticks, max force %.1f mN, max step %.2f mN; "
        "packets accepted %llu, dropped %llu\n  samples out of bounds: %llu dropped (%llu "
        "non-finite, %llu outside the workspace), %llu clamped\n",
        std::string(to_string(static_cast<Hand>(k))).c_str(),
        std::string(to_string(h.health)).c_str(), static_cast<unsigned long long>(h.samples),
        static_cast<unsigned long long>(h.zero_force_ticks), h.max_force_mn, h.max_force_step_mn,
        static_cast<unsigned long long>(h.counters.accepted),
        static_cast<unsigned long long>(h.counters.dropped()),
        static_cast<unsigned long long>(h.samples_non_finite + h.samples_outside_workspace),
        static_cast<unsigned long long>(h.samples_non_finite),
        static_cast<unsigned long long>(h.samples_outside_workspace),
        static_cast<unsigned long long>(h.samples_clamped));
    out += buf;
    out += line("latency", h.latency);
  }
  return out;
}

}  // namespace phaco
