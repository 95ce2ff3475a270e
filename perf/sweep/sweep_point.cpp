#include "perf/sweep/sweep_point.hpp"

#include <sys/wait.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <memory>
#include <sstream>

#include "engine/core/clock.hpp"
#include "engine/core/error.hpp"
#include "engine/haptics/scripted_device.hpp"
#include "perf/cores.hpp"
#include "perf/haptics/counting_device.hpp"
#include "procedures/haptics/haptic_session.hpp"
#include "procedures/scene/run.hpp"
#include "tests/engine/haptics/alloc_counter.hpp"

namespace phaco::perf {
namespace {

namespace fs = std::filesystem;

nlohmann::json finite_or_null(double v) {
  return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(nullptr);
}

// The haptic session beside the frames, but the scene keeps its scripted tracks: the device's
// samples are drained (as a device-driven scene would) and ignored, so the state hash is the
// same with and without the haptic thread. The model is published every frame as in the trainer.
class TrackKeepingPort final : public HapticPort {
 public:
  explicit TrackKeepingPort(HapticSession& session) : session_(session) {}
  bool newest_pose(Hand hand, ToolPose& pose) override {
    ToolPose drained = pose;
    session_.newest_pose(hand, drained);
    return false;
  }
  HapticModel& model_slot() override { return session_.model_slot(); }
  void publish_model() override { session_.publish_model(); }

 private:
  HapticSession& session_;
};

// VmRSS / VmHWM from /proc/self/status, MiB (0 where unreadable).
double status_mb(const char* key) {
  std::ifstream in("/proc/self/status");
  std::string line;
  const std::string k = std::string(key) + ":";
  while (std::getline(in, line)) {
    if (line.rfind(k, 0) == 0) return std::atof(line.c_str() + k.size()) / 1024.0;  // kB
  }
  return 0;
}

// Resets the peak resident set (VmHWM) to the current one (Linux ≥ 4.0, clear_refs "5").
void reset_peak_rss() {
  std::ofstream("/proc/self/clear_refs") << "5";
}

CostSummary summarise(const SystemTiming& t) {
  CostSummary c;
  c.name = t.name;
  c.p50_ms = t.p50_ms();
  c.p99_ms = t.p99_ms();
  if (!t.samples_ms.empty()) {
    c.max_ms = *std::max_element(t.samples_ms.begin(), t.samples_ms.end());
    double sum = 0;
    for (float v : t.samples_ms) sum += v;
    c.mean_ms = sum / static_cast<double>(t.samples_ms.size());
  }
  return c;
}

nlohmann::json cost_json(const CostSummary& c) {
  return {{"name", c.name},
          {"p50_ms", c.p50_ms},
          {"p99_ms", c.p99_ms},
          {"max_ms", c.max_ms},
          {"mean_ms", c.mean_ms}};
}
CostSummary cost_from(const nlohmann::json& j) {
  return {j.at("name"), j.at("p50_ms"), j.at("p99_ms"), j.at("max_ms"), j.at("mean_ms")};
}

Hand device_hand(const Scenario& s) {
  return s.find_hand(Hand::Right) ? Hand::Right : Hand::Left;
}

}  // namespace

SweepPointResult run_sweep_point(const SweepPointConfig& config) {
  SweepPointResult r;
  r.config = config;
  Scenario s = load_scenario(config.scenario);
  s.eye.level = config.level;
  if (!config.capsule_layout.empty()) s.eye.capsule_layout = config.capsule_layout;
  for (const auto& [k, v] : config.methods) s.methods[k] = v;
  if (config.dt_divisor < 1)
    throw InputError("sweep point: dt_divisor must be ≥ 1, got " +
                     std::to_string(config.dt_divisor));
  s.dt_s /= double(config.dt_divisor);  // the tracks are in seconds: the same motion, more frames

  SceneOptions options;
  options.threads = config.threads;
  options.dispatch = config.graph_every_frame ? Dispatch::Graph : Dispatch::Auto;
  if (!config.cache_dir.empty()) options.cache_dir = config.cache_dir;

  std::unique_ptr<HapticSession> session;
  std::unique_ptr<TrackKeepingPort> port;
  CountingDevice* probe = nullptr;
  if (config.haptics && !config.warm_only) {
    HapticSessionConfig hc;
    hc.loop.realtime = config.realtime;
    hc.loop.lock_memory = false;
    session = std::make_unique<HapticSession>(hc);
    const Hand hand = device_hand(s);
    if (!s.find_hand(hand))
      throw InputError(s.source + ": no hand with a track for the haptic device");
    ScriptedDeviceOptions device_options;
    device_options.hold_s = 1e6;  // keep the device alive however long the frames take
    auto counting = std::make_unique<CountingDevice>(
        std::make_unique<ScriptedDevice>(*s.find_hand(hand), device_options));
    probe = counting.get();
    session->attach(hand, std::move(counting));
    port = std::make_unique<TrackKeepingPort>(*session);
    options.haptics = port.get();
  }

  r.rss_before_mb = status_mb("VmRSS");
  auto scene = build_scene(s, options);
  r.mesh_load_s = scene->mesh_load_s;
  r.rss_scene_mb = status_mb("VmRSS");
  if (config.warm_only) {
    r.ok = true;
    return r;
  }
  reset_peak_rss();

  const uint64_t frames = s.frame_count();
  r.round_trip_before_ns = core_round_trip_ns();  // ≈ 20 ms; no haptic thread yet
  step(*scene);  // the first model before the haptic thread starts, as run_realtime does
  const bool countable = probe && test::haptic_allocation_counting_available();
  if (session) {
    if (countable) {
      test::open_allocation_window();
      probe->arm();
    }
    session->start();
  }
  Stopwatch wall;
  for (uint64_t f = 1; f < frames; ++f) step(*scene);
  r.wall_s = wall.elapsed_s();
  if (session) {
    session->stop();
    if (countable) test::close_allocation_window();
    const HapticSessionStats h = session->stats();
    r.haptic_fifo = h.realtime.fifo;
    r.haptic_detail = h.realtime.detail;
    r.haptic_ticks = double(h.loop.ticks);
    r.haptic_overruns = double(h.loop.overruns);
    r.haptic_missed = double(h.loop.missed_deadlines);
    r.period_p50_us = h.loop.period.p50_us;
    r.period_p99_us = h.loop.period.p99_us;
    r.period_p999_us = h.loop.period.p999_us;
    r.period_max_us = h.loop.period.max_us;
    r.spin_mean_us = h.loop.spin.mean_us;
    r.spin_p50_us = h.loop.spin.p50_us;
    r.spin_p99_us = h.loop.spin.p99_us;
    r.compute_mean_us = h.loop.compute.mean_us;
    r.compute_p50_us = h.loop.compute.p50_us;
    r.compute_p99_us = h.loop.compute.p99_us;
    r.haptic_allocations =
        countable && probe->marked() ? double(test::allocations_on_marked_threads()) : -1.0;
    for (const auto& b : session->period_bins())
      r.period_bins.push_back({double(b.low_us), double(b.width_us), double(b.count)});
  }
  r.rss_peak_mb = status_mb("VmHWM");
  r.round_trip_after_ns = core_round_trip_ns();

  r.frames = scene->frame;
  r.sim_s = scene->time_s;
  r.frame = summarise(scene->executor->frame_timing());
  r.frame.name = "frame";
  r.graph_frames = scene->executor->graph_frames();
  r.serial_frames = scene->executor->serial_frames();
  for (const auto& t : scene->executor->timings()) r.systems.push_back(summarise(t));
  const RunReport report = report_of(*scene);
  for (const auto& [k, v] : report.elements) {
    r.elements[k] = v;
    if (k != "tools") r.total_elements += v;
  }
  r.bytes_per_element = r.total_elements > 0 ? (r.rss_peak_mb - r.rss_before_mb) * 1048576.0 /
                                                   double(r.total_elements)
                                             : 0.0;
  r.metrics = report.metrics;
  r.physics = report.physics;
  r.state_hash = report.state_hash;
  r.ok = true;
  return r;
}

nlohmann::json to_json(const SweepPointConfig& c) {
  return {{"drill", c.drill},
          {"scenario", c.scenario.string()},
          {"level", c.level},
          {"threads", c.threads},
          {"capsule_layout", c.capsule_layout},
          {"methods", c.methods},
          {"variant", c.variant},
          {"dt_divisor", c.dt_divisor},
          {"haptics", c.haptics},
          {"graph_every_frame", c.graph_every_frame},
          {"realtime", c.realtime},
          {"warm_only", c.warm_only},
          {"cache_dir", c.cache_dir.string()}};
}

SweepPointConfig config_from_json(const nlohmann::json& j) {
  SweepPointConfig c;
  c.drill = j.at("drill");
  c.scenario = j.at("scenario").get<std::string>();
  c.level = j.at("level");
  c.threads = j.at("threads");
  c.capsule_layout = j.at("capsule_layout");
  c.methods = j.at("methods").get<std::map<std::string, std::string>>();
  c.variant = j.at("variant");
  c.dt_divisor = j.value("dt_divisor", 1);  // points saved before the reference had none
  c.haptics = j.at("haptics");
  c.graph_every_frame = j.value("graph_every_frame", false);  // points saved before it existed
  c.realtime = j.at("realtime");
  c.warm_only = j.at("warm_only");
  c.cache_dir = j.at("cache_dir").get<std::string>();
  return c;
}

nlohmann::json to_json(const SweepPointResult& r) {
  nlohmann::json systems = nlohmann::json::array();
  for (const auto& s : r.systems) systems.push_back(cost_json(s));
  return {{"config", to_json(r.config)},
          {"ok", r.ok},
          {"error", r.error},
          {"frames", r.frames},
          {"sim_s", r.sim_s},
          {"wall_s", r.wall_s},
          {"mesh_load_s", r.mesh_load_s},
          {"frame", cost_json(r.frame)},
          {"systems", systems},
          {"graph_frames", r.graph_frames},
          {"serial_frames", r.serial_frames},
          {"haptic_fifo", r.haptic_fifo},
          {"haptic_detail", r.haptic_detail},
          {"haptic_ticks", r.haptic_ticks},
          {"haptic_overruns", r.haptic_overruns},
          {"haptic_missed", r.haptic_missed},
          {"period_p50_us", r.period_p50_us},
          {"period_p99_us", r.period_p99_us},
          {"period_p999_us", r.period_p999_us},
          {"period_max_us", r.period_max_us},
          {"spin_mean_us", r.spin_mean_us},
          {"spin_p50_us", r.spin_p50_us},
          {"spin_p99_us", r.spin_p99_us},
          {"compute_mean_us", r.compute_mean_us},
          {"compute_p50_us", r.compute_p50_us},
          {"compute_p99_us", r.compute_p99_us},
          {"haptic_allocations", r.haptic_allocations},
          {"period_bins", r.period_bins},
          {"rss_before_mb", r.rss_before_mb},
          {"rss_scene_mb", r.rss_scene_mb},
          {"rss_peak_mb", r.rss_peak_mb},
          {"elements", r.elements},
          {"total_elements", r.total_elements},
          {"bytes_per_element", r.bytes_per_element},
          {"metrics", r.metrics},
          {"physics", r.physics},
          {"state_hash", r.state_hash},
          // null where not measured (JSON has no NaN)
          {"core_round_trip_ns",
           {finite_or_null(r.round_trip_before_ns), finite_or_null(r.round_trip_after_ns)}}};
}

SweepPointResult result_from_json(const nlohmann::json& j) {
  SweepPointResult r;
  r.config = config_from_json(j.at("config"));
  r.ok = j.at("ok");
  r.error = j.at("error");
  r.frames = j.at("frames");
  r.sim_s = j.at("sim_s");
  r.wall_s = j.at("wall_s");
  r.mesh_load_s = j.at("mesh_load_s");
  r.frame = cost_from(j.at("frame"));
  for (const auto& s : j.at("systems")) r.systems.push_back(cost_from(s));
  r.graph_frames = j.value("graph_frames", uint64_t{0});
  r.serial_frames = j.value("serial_frames", uint64_t{0});
  r.haptic_fifo = j.at("haptic_fifo");
  r.haptic_detail = j.at("haptic_detail");
  r.haptic_ticks = j.at("haptic_ticks");
  r.haptic_overruns = j.at("haptic_overruns");
  r.haptic_missed = j.at("haptic_missed");
  r.period_p50_us = j.at("period_p50_us");
  r.period_p99_us = j.at("period_p99_us");
  r.period_p999_us = j.at("period_p999_us");
  r.period_max_us = j.at("period_max_us");
  // Points saved before these were recorded have none.
  r.spin_mean_us = j.value("spin_mean_us", 0.0);
  r.spin_p50_us = j.value("spin_p50_us", 0.0);
  r.spin_p99_us = j.value("spin_p99_us", 0.0);
  r.compute_mean_us = j.value("compute_mean_us", 0.0);
  r.compute_p50_us = j.value("compute_p50_us", 0.0);
  r.compute_p99_us = j.value("compute_p99_us", 0.0);
  r.haptic_allocations = j.at("haptic_allocations");
  r.period_bins = j.at("period_bins").get<std::vector<std::array<double, 3>>>();
  r.rss_before_mb = j.at("rss_before_mb");
  r.rss_scene_mb = j.at("rss_scene_mb");
  r.rss_peak_mb = j.at("rss_peak_mb");
  r.elements = j.at("elements").get<std::map<std::string, uint64_t>>();
  r.total_elements = j.at("total_elements");
  r.bytes_per_element = j.at("bytes_per_element");
  r.metrics = j.at("metrics");
  r.physics = j.at("physics");
  r.state_hash = j.at("state_hash");
  if (const auto it = j.find("core_round_trip_ns");
      it != j.end() && it->is_array() && it->size() == 2) {
    if ((*it)[0].is_number()) r.round_trip_before_ns = (*it)[0];
    if ((*it)[1].is_number()) r.round_trip_after_ns = (*it)[1];
  }
  return r;
}

int sweep_point_main(const std::vector<std::string>& args) {
  if (args.size() != 2) {
    std::fprintf(stderr, "phaco-perf _sweep-point: expected IN.json OUT.json\n");
    return 2;
  }
  std::ifstream in(args[0]);
  if (!in) {
    std::fprintf(stderr, "phaco-perf _sweep-point: cannot read %s\n", args[0].c_str());
    return 2;
  }
  SweepPointConfig config;
  try {
    config = config_from_json(nlohmann::json::parse(in));
  } catch (const nlohmann::json::exception& e) {
    std::fprintf(stderr, "phaco-perf _sweep-point: %s is not a sweep point's configuration: %s\n",
                 args[0].c_str(), e.what());
    return 2;
  }
  SweepPointResult r;
  try {
    r = run_sweep_point(config);
  } catch (const std::exception& e) {
    r.config = config;
    r.ok = false;
    r.error = e.what();
  }
  std::ofstream out(args[1]);
  out << to_json(r).dump();
  return out ? 0 : 1;
}

SweepPointResult run_sweep_point_isolated(const SweepPointConfig& config, const fs::path& exe,
                                          const fs::path& work_dir) {
  fs::create_directories(work_dir);
  const fs::path in = work_dir / "point.in.json", out = work_dir / "point.out.json",
                 err = work_dir / "point.err";
  fs::remove(out);
  std::ofstream(in) << to_json(config).dump(1);
  auto quote = [](const fs::path& p) {
    std::string q = "'";
    for (char ch : p.string()) q += ch == '\'' ? std::string("'\\''") : std::string(1, ch);
    return q + "'";
  };
  const std::string cmd =
      quote(exe) + " _sweep-point " + quote(in) + " " + quote(out) + " 2> " + quote(err);
  const int status = std::system(cmd.c_str());
  std::ifstream result(out);
  if (status == 0 && result) {
    try {
      return result_from_json(nlohmann::json::parse(result));
    } catch (const std::exception& e) {
      SweepPointResult r;
      r.config = config;
      r.error = std::string("unreadable point result: ") + e.what();
      return r;
    }
  }
  SweepPointResult r;
  r.config = config;
  std::ifstream e(err);
  std::string line, last;
  while (std::getline(e, line))
    if (!line.empty()) last = line;
  std::ostringstream why;
  // std::system runs a shell: a child killed by signal N shows as the shell's exit status 128 + N.
  const int code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  if (WIFSIGNALED(status)) {
    why << "the point's process died of signal " << WTERMSIG(status);
  } else if (code > 128) {
    why << "the point's process died of signal " << code - 128;
  } else {
    why << "the point's process exited with status " << code;
  }
  if (!last.empty()) why << ": " << last;
  r.error = why.str();
  return r;
}

}  // namespace phaco::perf
