#include "procedures/trainer/trainer_session.hpp"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <future>

#include "engine/core/clock.hpp"
#include "engine/core/error.hpp"
#include "engine/core/utc_time.hpp"
#include "engine/haptics/device_factory.hpp"
#include "engine/records/record_location.hpp"
#include "engine/records/record_run.hpp"
#include "procedures/scene/drill_metrics.hpp"
#include "procedures/scene/run.hpp"
#include "procedures/trainer/live_ports.hpp"
#include "procedures/trainer/snapshot_fill.hpp"

namespace phaco {

namespace {

size_t at(Hand h) {
  return static_cast<size_t>(h) & 1u;
}

bool is_trackless(const std::string& spec) {
  return spec.empty() || spec == "track";
}

}  // namespace

TrainerSession::TrainerSession(TrainerConfig config)
    : config_(std::move(config)), desktop_(std::make_shared<DesktopInput>(config_.desktop)) {
  for (size_t h = 0; h < config_.devices.size(); ++h) {
    const std::string& spec = config_.devices[h];
    if (spec == "desktop" || is_trackless(spec)) continue;
    try {
      parse_device_spec(spec);
    } catch (const InputError& e) {  // which hand, and the trainer's own choices too
      throw InputError(std::string(to_string(static_cast<Hand>(h))) + " hand: " + e.what() +
                       " (or desktop, track)");
    }
  }
  if (config_.duration_s < 0 || !std::isfinite(config_.duration_s))
    throw InputError("trainer: duration must be ≥ 0 s");
}

TrainerSession::~TrainerSession() {
  stop();
}

void TrainerSession::start() {
  Scenario scenario = config_.scenario;
  if (config_.duration_s > 0) scenario.duration_s = config_.duration_s;
  launch(scenario, config_.devices);
}

void TrainerSession::launch(const Scenario& scenario, const std::array<std::string, 2>& devices) {
  stop();
  launched_scenario_ = scenario;
  launched_devices_ = devices;
  // Live inputs hold their tools in the ports (procedures/trainer/live_ports.hpp).
  running_scenario_ = with_live_ports(scenario, devices);
  running_devices_ = devices;
  const auto pivots = desktop_ports(running_scenario_, config_.scene.carried);
  if (!config_.trainee.empty()) {
    // Fail before the drill, not after it: the database opens and the name is acceptable.
    check_record_target(config_.records_db.empty() ? default_records_db() : config_.records_db,
                        config_.trainee);
  }
  haptics_ = std::make_unique<HapticSession>(config_.haptics);
  clock_.paused.store(false, std::memory_order_relaxed);
  clock_.paused_ns.store(0, std::memory_order_relaxed);
  const double duration = running_scenario_.duration_s;
  for (Hand h : {Hand::Left, Hand::Right}) {
    recorders_[at(h)].reset();
    const std::string& spec = devices[at(h)];
    const HandTrack* track = running_scenario_.find_hand(h);
    if (!track || is_trackless(spec)) continue;
    std::unique_ptr<Device> device;
    if (spec == "desktop") {
      desktop_->set_port(h, pivots[at(h)]);
      desktop_->set_start(h, track->tool, sample_track(track->track, 0.0));
      device = std::make_unique<DesktopDevice>(desktop_, h);
    } else {
      DeviceContext context;
      context.scenario = &running_scenario_;
      context.hand = h;
      device = make_device(spec, context);
    }
    // Capacity for the whole run at 1 kHz with a margin: recording never allocates.
    recorders_[at(h)] =
        std::make_unique<DeviceRecorder>(static_cast<std::size_t>(duration * 1500) + 4096);
    haptics_->attach(h, recording_device(std::move(device), *recorders_[at(h)], &clock_));
  }
  TrainerEvent stale;
  while (events_.try_pop(stale)) {
  }
  stop_.store(false, std::memory_order_relaxed);
  pause_.store(false, std::memory_order_relaxed);
  failed_.store(false, std::memory_order_relaxed);
  error_.clear();
  end_report_ = nlohmann::json::object();
  end_frames_ = 0;
  events_seen_ = 0;
  rate_t0_ns_ = 0;
  frame_.store(0, std::memory_order_relaxed);
  sim_time_s_.store(0, std::memory_order_relaxed);
  sim_rate_hz_.store(0, std::memory_order_relaxed);
  state_.store(static_cast<uint8_t>(TrainerState::Running), std::memory_order_release);

  auto started = std::make_shared<std::promise<void>>();
  std::future<void> ready = started->get_future();
  sim_ = std::thread([this, started] {
    bool signalled = false;
    try {
      SceneOptions options = config_.scene;
      RealtimeRunOptions run;
      // run_realtime steps once before its clock starts (the first model): the scenario's frame
      // count in all, as `phaco run` steps, so a run on tracks alone matches it bit for bit.
      const double dt = running_scenario_.dt_s;
      run.duration_s = std::max(running_scenario_.duration_s - dt, dt);
      run.loop_scenario = false;
      run.stop = &stop_;
      run.pause = &pause_;
      run.after_frame = [this, &started, &signalled](Scene& scene) {
        after_frame(scene);
        if (!signalled) started->set_value(), signalled = true;
      };
      run.at_end = [this](Scene& scene) { at_end(scene, nullptr); };
      const RealtimeRunReport report = run_realtime(running_scenario_, options, *haptics_, run);
      end_report_["live"] = to_json(report);
      end_report_["live"]["wall_s"] = report.wall_s;
    } catch (const std::exception& e) {
      error_ = e.what();
      failed_.store(true, std::memory_order_release);
      if (!signalled) started->set_exception(std::current_exception()), signalled = true;
    }
    state_.store(
        static_cast<uint8_t>(failed_.load(std::memory_order_relaxed) ? TrainerState::Idle
                                                                     : TrainerState::Ended),
        std::memory_order_release);
  });
  try {
    ready.get();  // the scene is built and its first snapshot published (or it failed)
    unfinished_ = true;
  } catch (...) {
    join();
    throw;
  }
}

void TrainerSession::after_frame(Scene& scene) {
  render::RenderSnapshot& snap = snapshots_.write_slot();
  fill_snapshot(scene, snap);
  const Hand selected = desktop_->selected();
  for (render::ToolView& t : snap.tools)
    t.selected = running_devices_[at(t.hand)] == "desktop" && t.hand == selected;
  snapshots_.publish();
  // Relaxed: figures for display; nothing is read on their strength.
  snapshots_published_.fetch_add(1, std::memory_order_relaxed);
  frame_.store(scene.frame, std::memory_order_relaxed);
  sim_time_s_.store(scene.time_s, std::memory_order_relaxed);
  const int64_t now = now_ns();
  if (rate_t0_ns_ == 0) {
    rate_t0_ns_ = now, rate_frame0_ = scene.frame;
  } else if (now - rate_t0_ns_ >= 500'000'000) {
    sim_rate_hz_.store(static_cast<double>(scene.frame - rate_frame0_) * 1e9 /
                           static_cast<double>(now - rate_t0_ns_),
                       std::memory_order_relaxed);
    rate_t0_ns_ = now, rate_frame0_ = scene.frame;
  }
  for (const size_t n = drill_event_count(scene); events_seen_ < n; ++events_seen_) {
    const LiveDrillEvent e = drill_event(scene, events_seen_);
    events_.try_push({e.t_s, e.kind, e.hand, e.detail, e.value});  // full: dropped, counted
  }
}

void TrainerSession::at_end(Scene& scene, const RealtimeRunReport*) {
  end_report_ = to_json(report_of(scene));  // as `phaco run --report`, wall_time_s 0
  end_frames_ = scene.frame;
  if (config_.at_end) config_.at_end(scene);
}

void TrainerSession::join() {
  if (sim_.joinable()) sim_.join();
}

void TrainerSession::stop() {
  unfinished_ = false;
  stop_.store(true, std::memory_order_release);
  pause_.store(false, std::memory_order_release);
  join();
  if (state() != TrainerState::Idle)
    state_.store(static_cast<uint8_t>(TrainerState::Idle), std::memory_order_release);
}

TrainerState TrainerSession::state() const {
  return static_cast<TrainerState>(state_.load(std::memory_order_acquire));
}

void TrainerSession::pause() {
  if (state() != TrainerState::Running) return;
  paused_at_ns_ = now_ns();
  clock_.paused.store(true, std::memory_order_relaxed);
  pause_.store(true, std::memory_order_release);
  state_.store(static_cast<uint8_t>(TrainerState::Paused), std::memory_order_release);
}

void TrainerSession::resume() {
  if (state() != TrainerState::Paused) return;
  clock_.paused_ns.fetch_add(now_ns() - paused_at_ns_, std::memory_order_relaxed);
  clock_.paused.store(false, std::memory_order_relaxed);
  state_.store(static_cast<uint8_t>(TrainerState::Running), std::memory_order_release);
  pause_.store(false, std::memory_order_release);
}

void TrainerSession::reset() {
  if (!launched_scenario_) return start();
  // Copies: launch() overwrites the members they come from.
  const Scenario scenario = *launched_scenario_;
  const std::array<std::string, 2> devices = launched_devices_;
  launch(scenario, devices);
}

nlohmann::json TrainerSession::finish() {
  if (!unfinished_) throw InputError("trainer: finish() without a run: start() first");
  unfinished_ = false;
  stop_.store(true, std::memory_order_release);
  pause_.store(false, std::memory_order_release);
  join();
  state_.store(static_cast<uint8_t>(TrainerState::Idle), std::memory_order_release);
  if (failed_.load(std::memory_order_acquire)) throw InputError("trainer: " + error_);

  nlohmann::json report = end_report_;
  const double dt = running_scenario_.dt_s;
  // The recording: the scenario with every device-driven hand's track replaced by what its
  // device produced, as long as the simulated run (not the script).
  Scenario recorded = running_scenario_;
  nlohmann::json from = nlohmann::json::object();
  for (Hand h : {Hand::Left, Hand::Right}) {
    const DeviceRecorder* r = recorders_[at(h)].get();
    const HandTrack* track = running_scenario_.find_hand(h);
    if (!track) continue;
    from[std::string(to_string(h))] = {{"device", running_devices_[at(h)]},
                                       {"samples", r ? r->size() : 0},
                                       {"dropped", r ? r->dropped() : 0}};
    if (r && r->size() > 0) recorded = r->scenario(recorded, h, track->tool);
  }
  recorded.duration_s = std::max(static_cast<double>(end_frames_) * dt, dt);
  recorded.description = "Recorded in the trainer; " + recorded.description;
  last_recording_ = recorded;

  if (!config_.trainee.empty()) {
    // The stored report is the fixed-step replay of the recording: replaying the record gives
    // its metrics and state hash exactly (docs/records.md).
    SceneOptions options = config_.scene;
    options.haptics = nullptr;
    nlohmann::json j = to_json(run_scenario(recorded, options));
    j["date"] = utc_now();
    j["live"] = report.value("live", nlohmann::json::object());
    j["live_metrics"] = report.value("metrics", nlohmann::json::object());
    j["live_state_hash"] = report.value("state_hash", std::string());
    j["recorded_from"] = from;
    const std::filesystem::path db =
        config_.records_db.empty() ? default_records_db() : config_.records_db;
    // The drill took the live run's wall time (pauses left out), not the replay's.
    const double run_s = j["live"].value("wall_s", 0.0);
    const double finished_s = unix_now_s();
    for (UnsavedRun& u : unsaved_) u.is_last = false;
    try {
      j["record_id"] = record_run(db, config_.trainee, recorded, j, run_s, finished_s);
    } catch (const InputError& e) {
      // The database failed at the worst moment, after the drill: keep the drill, say why, and
      // let the trainee save it again (save_unsaved) once the cause is fixed.
      unsaved_.push_back({db, config_.trainee, recorded, j, run_s, finished_s, true});
      j["save_error"] = e.what();
    }
    report = std::move(j);
  } else {
    report["recorded_from"] = from;
  }
  last_report_ = report;
  return report;
}

std::vector<int64_t> TrainerSession::save_unsaved() {
  std::vector<int64_t> ids;
  while (!unsaved_.empty()) {
    UnsavedRun& u = unsaved_.front();
    const int64_t id = record_run(u.db, u.trainee, u.recording, u.report, u.run_s, u.finished_s);
    ids.push_back(id);
    if (u.is_last) {
      last_report_.erase("save_error");
      last_report_["record_id"] = id;
    }
    unsaved_.erase(unsaved_.begin());
  }
  return ids;
}

void TrainerSession::take_unsaved_from(TrainerSession& other) {
  if (&other == this) return;
  for (UnsavedRun& u : other.unsaved_) {
    u.is_last = false;
    unsaved_.push_back(std::move(u));
  }
  other.unsaved_.clear();
}

std::vector<std::filesystem::path> TrainerSession::write_unsaved(
    const std::filesystem::path& dir) const {
  std::vector<std::filesystem::path> files;
  if (unsaved_.empty()) return files;
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (ec) throw InputError(dir.string() + ": cannot create the folder: " + ec.message());
  for (const UnsavedRun& u : unsaved_) {
    // The finishing time in the name keeps files from different drills and sessions apart.
    std::string stamp = format_utc(u.finished_s);
    std::replace(stamp.begin(), stamp.end(), ':', '-');
    const std::filesystem::path file =
        dir / (std::string(to_string(u.recording.drill)) + "-" + stamp + ".json");
    nlohmann::json j = to_json(u.recording);
    // The database as shown: a server URI's password must not land in a file.
    const std::string db = shown_location(u.db.string());
    j["description"] = "Unsaved trainer drill of '" + u.trainee + "' (the records database " + db +
                       " refused it); store it with: phaco run FILE --record " + db +
                       " --trainee NAME";
    std::ofstream out(file, std::ios::binary);
    out << j.dump(2) << "\n";
    if (!out) throw InputError(file.string() + ": cannot write the unsaved drill");
    files.push_back(file);
  }
  return files;
}

void TrainerSession::replay_last() {
  if (!last_recording_) throw InputError("trainer: nothing to replay: no run was finished");
  const Scenario recording = *last_recording_;
  launch(recording, {"track", "track"});
}

const render::RenderSnapshot* TrainerSession::newest_snapshot() {
  if (snapshots_.acquire()) have_snapshot_ = true;
  return have_snapshot_ ? &snapshots_.read_slot() : nullptr;
}

TrainerStatus TrainerSession::status() const {
  TrainerStatus s;
  s.state = state();
  s.frame = frame_.load(std::memory_order_relaxed);
  s.sim_time_s = sim_time_s_.load(std::memory_order_relaxed);
  s.duration_s = running_scenario_.duration_s;
  s.sim_rate_hz = sim_rate_hz_.load(std::memory_order_relaxed);
  s.snapshots_published = snapshots_published_.load(std::memory_order_relaxed);
  s.events_dropped = events_.dropped();
  if (haptics_) {
    const HapticSessionStats h = haptics_->stats();
    s.haptic_period_p50_us = h.loop.period.p50_us;
    s.haptic_period_p99_us = h.loop.period.p99_us;
    s.haptic_ticks = h.loop.ticks;
    s.haptic_loop = h.loop;
    s.haptic_fifo = h.realtime.fifo;
    s.haptic_spin_margin_ns = h.spin_margin_ns;
  }
  if (failed_.load(std::memory_order_acquire)) s.error = error_;
  return s;
}

void TrainerSession::merge_haptic_period_into(DurationHistogram& into) const {
  if (haptics_) into.merge(haptics_->period_histogram());
}

size_t TrainerSession::poll_events(std::vector<TrainerEvent>& out) {
  return events_.drain([&out](const TrainerEvent& e) { out.push_back(e); });
}

}  // namespace phaco
