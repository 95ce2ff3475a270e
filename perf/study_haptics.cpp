// phaco-perf haptics (issue 6): the 1 kHz haptic thread. Beside the running capsulorhexis scene:
// period, wake-up lateness, force computation time, sample → force latency and allocations on the
// haptic thread, with and without real-time priority; force continuity with models at 30 Hz and
// with a 200 ms simulation stall. The loop alone under a busy second core (sleep + spin against
// sleep only). The local model's passive stiffness limit against the rate next to Colgate's bound,
// its continuity with and without the crossfade, and its cost per tick against the node count.
// The UDP bridge on loopback: round trip and silence → zero force. Measurements live in
// perf/haptics/; this file runs, tabulates, charts and writes the section.
#include <cmath>
#include <string>
#include <vector>

#include "engine/core/error.hpp"
#include "perf/haptics/loop_measure.hpp"
#include "perf/haptics/scene_haptics_measure.hpp"
#include "perf/haptics/stability_measure.hpp"
#include "perf/plot.hpp"
#include "perf/report.hpp"
#include "perf/studies.hpp"

namespace phaco::perf {
namespace {

std::string met(bool ok) {
  return ok ? "met" : "**missed**";
}

std::string scene_section(const std::vector<SceneHapticsRow>& rows,
                          const std::filesystem::path& dir) {
  Table t;
  t.columns = {
      "case",           "seconds",        "fifo",           "memory_locked",  "model_interval_ms",
      "stall_ms",       "ticks",          "overruns",       "missed",         "period_p50_us",
      "period_p99_us",  "period_p999_us", "period_max_us",  "late_p50_us",    "late_p99_us",
      "late_max_us",    "compute_p50_us", "compute_p99_us", "compute_max_us", "latency_p50_us",
      "latency_p99_us", "latency_max_us", "allocations",    "max_force_mn",   "max_force_step_mn",
      "models",         "frames",         "frame_p50_ms",   "frame_p99_ms",   "late_frames",
      "steal_ms"};
  for (const auto& r : rows)
    t.add({r.c.label,
           r.c.seconds,
           double(r.fifo),
           double(r.memory_locked),
           r.c.model_interval_ms,
           r.c.stall_ms,
           r.ticks,
           r.overruns,
           r.missed,
           r.period_p50_us,
           r.period_p99_us,
           r.period_p999_us,
           r.period_max_us,
           r.late_p50_us,
           r.late_p99_us,
           r.late_max_us,
           r.compute_p50_us,
           r.compute_p99_us,
           r.compute_max_us,
           r.latency_p50_us,
           r.latency_p99_us,
           r.latency_max_us,
           r.allocations,
           r.max_force_mn,
           r.max_force_step_mn,
           r.models,
           r.frames,
           r.frame_p50_ms,
           r.frame_p99_ms,
           r.late_frames,
           r.steal_ms});
  write_csv(t, dir / "haptics_scene.csv");
  write_json(t, dir / "haptics_scene.json");

  std::string md = "### Beside the running scene\n\n";
  md +=
      "The default capsulorhexis scene (`capsulorhexis_demo.json`, level 3) stepped in real time "
      "at 120 Hz "
      "on the simulation thread while the haptic thread renders the forceps hand from a scripted "
      "device "
      "(the scene's own track; the scene restarts when its 40 s end). Period: wake-up to wake-up; "
      "lateness: "
      "wake-up after the deadline; compute: the tick's own work (device read, model, force, "
      "write); latency: "
      "a device sample's arrival to the force computed from it being written. Allocations: made on "
      "the haptic "
      "thread after its first tick (global operator new, counted per thread).\n\n";
  md +=
      "| case | priority | s | period p50 / p99 / p99.9 / max (us) | lateness p50 / p99 / max (us) "
      "| compute p50 / "
      "p99 / max (us) | latency p50 / p99 / max (us) | overruns | allocations | max force (mN) | "
      "max step (mN) | "
      "models | late frames | stolen (ms) "
      "|\n|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n";
  for (const auto& r : rows) {
    md += "| " + r.c.label + " | " + (r.fifo ? "SCHED_FIFO" : "normal") + " | " +
          fmt("%.0f", r.c.seconds) + " | " + fmt("%.1f", r.period_p50_us) + " / " +
          fmt("%.1f", r.period_p99_us) + " / " + fmt("%.1f", r.period_p999_us) + " / " +
          fmt("%.0f", r.period_max_us) + " | " + fmt("%.1f", r.late_p50_us) + " / " +
          fmt("%.1f", r.late_p99_us) + " / " + fmt("%.0f", r.late_max_us) + " | " +
          fmt("%.1f", r.compute_p50_us) + " / " + fmt("%.1f", r.compute_p99_us) + " / " +
          fmt("%.0f", r.compute_max_us) + " | " + fmt("%.1f", r.latency_p50_us) + " / " +
          fmt("%.1f", r.latency_p99_us) + " / " + fmt("%.0f", r.latency_max_us) + " | " +
          fmt("%.0f", r.overruns) + " | " +
          (r.allocations < 0 ? std::string("n/a") : fmt("%.0f", r.allocations)) + " | " +
          fmt("%.1f", r.max_force_mn) + " | " + fmt("%.2f", r.max_force_step_mn) + " | " +
          fmt("%.0f", r.models) + " | " + fmt("%.0f", r.late_frames) + " | " +
          fmt("%.0f", r.steal_ms) + " |\n";
  }
  md += "\n";
  for (const auto& r : rows) {
    if (!(r.fifo && r.c.model_interval_ms == 0 && r.c.stall_ms == 0)) continue;
    md += "Targets with real-time priority (" + r.c.label + "): period p99 ≤ 1.02 ms " +
          met(r.period_p99_us <= 1020) + " (" + fmt("%.1f", r.period_p99_us) +
          " us); max ≤ 1.5 ms " + met(r.period_max_us <= 1500) + " (" +
          fmt("%.0f", r.period_max_us) + " us); lateness p99 ≤ 20 us " + met(r.late_p99_us <= 20) +
          " (" + fmt("%.1f", r.late_p99_us) + " us); zero allocations " + met(r.allocations == 0) +
          ".\n\n";
  }
  for (const auto& r : rows) {
    if (r.c.model_interval_ms == 0 && r.c.stall_ms == 0) continue;
    const double fraction = r.max_force_mn > 0 ? r.max_force_step_mn / r.max_force_mn : 0;
    md += "Continuity, " + r.c.label + ": the largest change between two ticks was " +
          fmt("%.2f", r.max_force_step_mn) + " mN, " + fmt("%.1f", 100 * fraction) +
          " % of the largest force (" + fmt("%.1f", r.max_force_mn) + " mN).\n\n";
  }
  for (const auto& r : rows) {
    if (r.c.realtime && !r.fifo) {
      md += "Real-time priority was asked for but not granted (" + r.realtime_detail +
            "); `phaco run --haptics` prints a warning in that case.\n\n";
      break;
    }
  }
  return md;
}

std::string loop_section(const std::vector<LoopMeasureRow>& rows,
                         const std::filesystem::path& dir) {
  Table t;
  t.columns = {"case",           "fifo",          "spin_us",     "load",          "work_us",
               "seconds",        "ticks",         "overruns",    "period_p50_us", "period_p99_us",
               "period_p999_us", "period_max_us", "late_p50_us", "late_p99_us",   "late_max_us",
               "spun_p50_us",    "spun_p99_us"};
  for (const auto& r : rows)
    t.add({r.label, double(r.status.fifo), double(r.settings.spin_ns) * 1e-3,
           std::string(loop_load_name(r.load)), double(r.work_ns) * 1e-3, r.seconds,
           double(r.stats.ticks), double(r.stats.overruns), r.stats.period.p50_us,
           r.stats.period.p99_us, r.stats.period.p999_us, r.stats.period.max_us,
           r.stats.lateness.p50_us, r.stats.lateness.p99_us, r.stats.lateness.max_us,
           r.stats.spin.p50_us, r.stats.spin.p99_us});
  write_csv(t, dir / "haptics_loop.csv");
  write_json(t, dir / "haptics_loop.json");
  std::string md = "### The loop alone, the other core busy\n\n";
  md +=
      "The loop pinned to CPU 0 with a fixed amount of work per tick, a busy thread pinned to CPU "
      "1; sleep "
      "with `clock_nanosleep` to the deadline minus a margin, then spin on the clock; the margin "
      "is fixed, or follows the wake-up latency the loop observes (engine/haptics/"
      "spin_margin.hpp). *Spun*: the time the loop actually spun per tick, the margin's CPU "
      "cost.\n\n";
  md +=
      "| case | priority | spin (us) | s | period p50 / p99 / p99.9 / max (us) | lateness p50 / "
      "p99 / max (us) | spun p50 / p99 (us) | "
      "overruns |\n|---|---|---|---|---|---|---|---|\n";
  for (const auto& r : rows) {
    md += "| " + r.label + " | " + (r.status.fifo ? "SCHED_FIFO" : "normal") + " | " +
          fmt("%.0f", double(r.settings.spin_ns) * 1e-3) +
          (r.settings.max_spin_ns > r.settings.spin_ns && r.settings.spin_ns > 0
               ? "–" + fmt("%.0f", double(r.settings.max_spin_ns) * 1e-3)
               : std::string()) +
          " | " + fmt("%.1f", r.seconds) + " | " + fmt("%.1f", r.stats.period.p50_us) + " / " +
          fmt("%.1f", r.stats.period.p99_us) + " / " + fmt("%.1f", r.stats.period.p999_us) + " / " +
          fmt("%.0f", r.stats.period.max_us) + " | " + fmt("%.1f", r.stats.lateness.p50_us) +
          " / " + fmt("%.1f", r.stats.lateness.p99_us) + " / " +
          fmt("%.0f", r.stats.lateness.max_us) + " | " + fmt("%.1f", r.stats.spin.p50_us) + " / " +
          fmt("%.1f", r.stats.spin.p99_us) + " | " + fmt("%.0f", double(r.stats.overruns)) + " |\n";
  }
  return md + "\n";
}

std::string stability_section(const std::vector<StiffnessLimitRow>& limits,
                              const std::vector<ContinuityRow>& cont,
                              const std::vector<TickCostRow>& cost,
                              const std::filesystem::path& dir) {
  Table t;
  t.columns = {"scene",
               "rate_hz",
               "device_mass_kg",
               "device_damping_mn_s_per_mm",
               "passive_limit_mn_per_mm",
               "colgate_bound_mn_per_mm"};
  for (const auto& r : limits)
    t.add({r.scene, r.rate_hz, r.device_mass_kg, r.device_damping_mn_s_per_mm,
           r.passive_limit_mn_per_mm, r.colgate_bound_mn_per_mm});
  write_csv(t, dir / "haptics_stiffness.csv");
  write_json(t, dir / "haptics_stiffness.json");

  Chart c{.title = "Largest passive stiffness against the haptic rate",
          .x = {"haptic rate (Hz)", Scale::Log10},
          .y = {"stiffness (mN/mm)", Scale::Log10}};
  // Per scene: the measured limit and its own bound (each scene's device damping b differs).
  std::vector<Series> measured, bounds;
  for (const auto& r : limits) {
    size_t k = 0;
    while (k < measured.size() && measured[k].name != r.scene) ++k;
    if (k == measured.size()) {
      measured.push_back(Series{.name = r.scene});
      bounds.push_back(Series{.name = "2b/T, " + r.scene, .dashed = true});
    }
    measured[k].x.push_back(r.rate_hz), measured[k].y.push_back(r.passive_limit_mn_per_mm);
    bounds[k].x.push_back(r.rate_hz), bounds[k].y.push_back(r.colgate_bound_mn_per_mm);
  }
  for (size_t k = 0; k < measured.size(); ++k)
    c.series.push_back(measured[k]), c.series.push_back(bounds[k]);
  save_chart(c, dir / "haptics_stiffness.png");

  std::string md = "### Stability of the local model: passive stiffness against rate\n\n";
  md +=
      "A simulated device (mass m, physical damping b, force held between ticks) against a virtual "
      "wall and "
      "holding a grasped membrane; the largest stiffness whose energy does not grow, found by "
      "bisection, next "
      "to Colgate & Schenkel's bound K < 2b/T (docs/haptic_model.md).\n\n"
      "![passive stiffness against rate](results/haptics_stiffness.png)\n\n";
  md +=
      "| scene | rate (Hz) | m (kg) | b (mN s/mm) | passive limit (mN/mm) | 2b/T (mN/mm) "
      "|\n|---|---|---|---|---|---|\n";
  for (const auto& r : limits)
    md += "| " + r.scene + " | " + fmt("%.0f", r.rate_hz) + " | " + fmt("%.3g", r.device_mass_kg) +
          " | " + fmt("%.3g", r.device_damping_mn_s_per_mm) + " | " +
          fmt("%.4g", r.passive_limit_mn_per_mm) + " | " + fmt("%.4g", r.colgate_bound_mn_per_mm) +
          " |\n";

  Table tc;
  tc.columns = {"models", "crossfade", "range_mn", "max_jump_mn", "jump_fraction"};
  for (const auto& r : cont)
    tc.add({r.models, double(r.crossfade), r.range_mn, r.max_jump_mn, r.jump_fraction});
  write_csv(tc, dir / "haptics_continuity.csv");
  write_json(tc, dir / "haptics_continuity.json");
  md +=
      "\n### Continuity of the local model\n\nA membrane moving under the tool, models arriving as "
      "listed; the "
      "largest change of force between two ticks as a fraction of the force's range.\n\n";
  md +=
      "| models | crossfade | range (mN) | largest jump (mN) | fraction |\n|---|---|---|---|---|\n";
  for (const auto& r : cont)
    md += "| " + r.models + " | " + (r.crossfade ? "on" : "off") + " | " + fmt("%.2f", r.range_mn) +
          " | " + fmt("%.3f", r.max_jump_mn) + " | " + fmt("%.3f", r.jump_fraction) + " |\n";

  Table tt;
  tt.columns = {"nodes",  "springs", "triangles",          "ticks",         "mean_ns",
                "p99_ns", "max_ns",  "mean_cg_iterations", "adopt_mean_ns", "blend_mean_ns"};
  for (const auto& r : cost)
    tt.add({double(r.nodes), double(r.springs), double(r.triangles), double(r.ticks), r.mean_ns,
            r.p99_ns, r.max_ns, r.mean_cg_iterations, r.adopt_mean_ns, r.blend_mean_ns});
  write_csv(tt, dir / "haptics_tick_cost.csv");
  write_json(tt, dir / "haptics_tick_cost.json");
  Chart ct{.title = "One haptic tick against the local node count",
           .x = {"local nodes", Scale::Linear},
           .y = {"us per tick", Scale::Linear}};
  Series mean{.name = "mean"}, p99{.name = "p99"}, blend{.name = "mean during a crossfade"};
  for (const auto& r : cost) {
    mean.x.push_back(r.nodes), mean.y.push_back(r.mean_ns * 1e-3);
    p99.x.push_back(r.nodes), p99.y.push_back(r.p99_ns * 1e-3);
    blend.x.push_back(r.nodes), blend.y.push_back(r.blend_mean_ns * 1e-3);
  }
  ct.series = {mean, p99, blend};
  save_chart(ct, dir / "haptics_tick_cost.png");
  md +=
      "\n### Cost of a tick\n\nOne `haptic_tick` (tool on a membrane patch, implicit step of the "
      "local nodes "
      "by CG) against the node count, and the crossfade (two models ticked).\n\n"
      "![tick cost](results/haptics_tick_cost.png)\n\n";
  md +=
      "| nodes | springs | triangles | mean (us) | p99 (us) | max (us) | CG iterations | adopt "
      "(us) | crossfade tick "
      "(us) |\n|---|---|---|---|---|---|---|---|---|\n";
  for (const auto& r : cost)
    md += "| " + fmt("%.0f", r.nodes) + " | " + fmt("%.0f", r.springs) + " | " +
          fmt("%.0f", r.triangles) + " | " + fmt("%.2f", r.mean_ns * 1e-3) + " | " +
          fmt("%.2f", r.p99_ns * 1e-3) + " | " + fmt("%.1f", r.max_ns * 1e-3) + " | " +
          fmt("%.1f", r.mean_cg_iterations) + " | " + fmt("%.2f", r.adopt_mean_ns * 1e-3) + " | " +
          fmt("%.2f", r.blend_mean_ns * 1e-3) + " |\n";
  return md + "\n";
}

std::string udp_section(const UdpBridgeRow& r, const std::filesystem::path& dir) {
  Table t;
  t.columns = {"seconds",
               "sent",
               "accepted",
               "dropped",
               "forces_received",
               "round_trip_p50_us",
               "round_trip_p99_us",
               "round_trip_max_us",
               "silence_timeout_ms",
               "silence_to_zero_ms"};
  t.add({r.seconds, r.sent, r.accepted, r.dropped, r.forces_received, r.round_trip_p50_us,
         r.round_trip_p99_us, r.round_trip_max_us, r.silence_timeout_ms, r.silence_to_zero_ms});
  write_csv(t, dir / "haptics_udp.csv");
  write_json(t, dir / "haptics_udp.json");
  std::string md = "### The UDP bridge on loopback\n\n";
  md +=
      "A peer thread sends the forceps track at 1 kHz to a UDP bridge device driving the scene in "
      "real time and "
      "reads the force packets back; each force packet echoes the send time of the pose it was "
      "computed from, "
      "so the round trip is pose sent → force received (both network legs, the I/O thread and the "
      "haptic "
      "tick). The peer then goes silent.\n\n";
  md +=
      "| s | sent | accepted | dropped | forces back | round trip p50 / p99 / max (us) | silence "
      "timeout (ms) | "
      "last pose → zero force at the peer (ms) |\n|---|---|---|---|---|---|---|---|\n";
  md += "| " + fmt("%.0f", r.seconds) + " | " + fmt("%.0f", r.sent) + " | " +
        fmt("%.0f", r.accepted) + " | " + fmt("%.0f", r.dropped) + " | " +
        fmt("%.0f", r.forces_received) + " | " + fmt("%.0f", r.round_trip_p50_us) + " / " +
        fmt("%.0f", r.round_trip_p99_us) + " / " + fmt("%.0f", r.round_trip_max_us) + " | " +
        fmt("%.0f", r.silence_timeout_ms) + " | " +
        (r.silence_to_zero_ms < 0 ? std::string("not seen") : fmt("%.2f", r.silence_to_zero_ms)) +
        " |\n\n";
  md += "Target: force zero at the peer within 5 ms of the last pose sent: " +
        met(r.silence_to_zero_ms >= 0 && r.silence_to_zero_ms <= 5.0) + ".\n\n";
  return md;
}

}  // namespace

void run_haptics(const StudyOptions& options) {
  for (const auto& e : options.extra) throw InputError("haptics: unknown option '" + e + "'");
  const std::string load = load_note();
  const auto dir = options.out_dir / "results";
  Progress progress(5);
  const double long_s = options.quick ? 5 : 60,
               short_s = options.quick ? 6 : 15;  // the forceps grasp at 3.5 s

  progress.step("haptics: beside the scene");
  std::vector<SceneHapticsCase> cases = {
      {.label = "real-time priority", .seconds = long_s, .realtime = true},
      {.label = "normal priority", .seconds = long_s, .realtime = false},
      {.label = "models at 30 Hz",
       .seconds = short_s,
       .realtime = true,
       .model_interval_ms = 1000.0 / 30.0},
      {.label = "200 ms stall",
       .seconds = short_s,
       .realtime = true,
       .stall_at_s = 4.2,
       .stall_ms = 200},
  };
  const auto scene_rows = measure_scene_haptics(cases);

  progress.step("haptics: the loop alone");
  const auto loop_rows = measure_loop(default_loop_cases(options.quick ? 1.0 : 5.0));

  progress.step("haptics: stability and cost of the local model");
  const auto limits = measure_stiffness_limits();
  const auto cont = measure_continuity();
  const auto cost = measure_tick_cost({}, options.quick ? 2000 : 20000);

  progress.step("haptics: UDP bridge");
  const auto udp = measure_udp_bridge(options.quick ? 3.0 : 10.0);
  progress.step("haptics: writing");

  std::string md = "## Haptics: the 1 kHz thread (issue 6)\n\n";
  md += std::string("Measured by `phaco-perf haptics") + (options.quick ? " --quick" : "") + "`, " +
        load + ".\n\n";
  md += scene_section(scene_rows, dir);
  md += loop_section(loop_rows, dir);
  md += stability_section(limits, cont, cost, dir);
  md += udp_section(udp, dir);
  write_section(dir, "haptics", md);
  progress.finish();
}

}  // namespace phaco::perf
