#pragma once
// The trainer's simulation and haptics behind its UI (issue 8 items 3 and 4; DESIGN.md §5;
// docs/trainer_threads.md):
//
//   haptic thread (1 kHz)   HapticSession: devices → SPSC ring → the scene; local model → force
//   simulation thread       run_realtime: the scene stepped in real time at its dt; after every
//                           frame fill_snapshot into the snapshot triple buffer's write slot,
//                           publish; status figures (atomics) and new drill events (SPSC ring)
//   UI / render thread      this object's methods: start/pause/resume/reset/finish, the newest
//                           snapshot, the live status and events, the DesktopInput
//
// Neither the simulation nor the haptic thread ever waits for the UI: the snapshot and the
// events go through wait-free handoffs (a slow renderer gets fewer, newer snapshots; events
// beyond the ring's capacity are dropped and counted). All methods are for ONE UI thread.
//
// Devices per hand, by spec: "desktop" (DesktopInput: mouse/keyboard/gamepad), "track" (no
// device: the scene plays the scenario's track of that hand at simulated time, bit for bit as
// `phaco run`), or any engine/haptics/device_factory spec: "scripted", "replay:FILE",
// "udp:LOCALPORT@HOST:PORT", "openhaptics[:NAME]". A hand the scenario does not script has no
// tool and takes no device.
#include <array>
#include <atomic>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "engine/haptics/loop_stats.hpp"
#include "engine/haptics/recording_device.hpp"
#include "engine/haptics/spsc_ring.hpp"
#include "engine/haptics/triple_buffer.hpp"
#include "engine/render/snapshot.hpp"
#include "procedures/haptics/haptic_session.hpp"
#include "procedures/haptics/realtime_run.hpp"
#include "procedures/scene/scene.hpp"
#include "procedures/trainer/desktop_input.hpp"

namespace phaco {

struct TrainerConfig {
  Scenario scenario;  // the drill: eye, methods, dt; its tracks give the tools and start poses
  // Device spec per hand, indexed by Hand (Left, Right).
  std::array<std::string, 2> devices{"desktop", "desktop"};
  double duration_s = 0;  // simulated seconds before the drill ends by itself; 0: the scenario's
  SceneOptions scene;     // threads, mesh cache (haptics is set by the session)
  HapticSessionConfig haptics;
  DesktopMapping desktop;
  // finish() stores the run for this trainee (empty: not stored) in `records_db` (empty: the
  // default, default_records_db() of engine/records/record_run.hpp).
  std::string trainee;
  std::filesystem::path records_db;
  // Called on the simulation thread with the scene at the end of each live run (the procedure
  // mode takes the eye it leaves from there: apps/trainer/trainer_procedure.hpp); may be empty.
  std::function<void(Scene&)> at_end;
};

enum class TrainerState : uint8_t {
  Idle,  // not started, or finished
  Running,
  Paused,
  Ended,  // the duration was reached: the last snapshot stays, finish() gives the report
};

// A drill event as it happens (drill_metrics' live view): runout_warning, radial_tearout,
// capsule_breach, corneal_stress, port_stress, grasp, release, lens_contact, ... `kind` and
// `detail` point to string literals.
struct TrainerEvent {
  double t_s = 0;
  const char* kind = "";
  int hand = -1;  // Hand index, −1: the drill's own
  const char* detail = nullptr;
  double value = 0;
};

struct TrainerStatus {
  TrainerState state = TrainerState::Idle;
  uint64_t frame = 0;
  double sim_time_s = 0;
  double duration_s = 0;
  double sim_rate_hz = 0;  // frames per wall second over the last ~0.5 s
  double step_p50_ms = 0;  // not kept live: see finish()'s "live" report
  double haptic_period_p50_us = 0, haptic_period_p99_us = 0;
  int64_t haptic_ticks = 0;
  // Why a period ran long (--stats): the loop's full figures (engine/haptics/loop_stats.hpp):
  // a late wake-up (lateness), a long tick (compute), a deadline skipped (overruns).
  LoopStatsSnapshot haptic_loop;
  bool haptic_fifo = false;  // SCHED_FIFO granted to the haptic thread
  // The haptic loop's learned spin margin, ns: where the next procedure step's loop starts
  // (LoopSettings::start_margin_ns, apps/trainer/trainer_app.cpp).
  int64_t haptic_spin_margin_ns = 0;
  uint64_t snapshots_published = 0;
  uint64_t events_dropped = 0;  // the event ring was full (the UI did not poll)
  std::string error;            // the simulation thread's exception, if it stopped on one
};

class TrainerSession {
 public:
  // Checks the config (device specs, trainee) without building anything; throws InputError.
  explicit TrainerSession(TrainerConfig config);
  ~TrainerSession();  // stops without recording
  TrainerSession(const TrainerSession&) = delete;
  TrainerSession& operator=(const TrainerSession&) = delete;

  // Builds the scene (meshes from the cache: may take a while on a cold cache), makes the
  // devices, starts the haptic and simulation threads. Throws InputError (bad scenario or
  // device); a running session is stopped first.
  void start();
  void pause();
  void resume();
  // Stops without recording, rebuilds the scene from the scenario and starts again.
  void reset();
  // Stops (if running) and returns the drill's report JSON (as `phaco run --report`: metrics,
  // score, events, series, state hash) with the live run's real-time figures under "live". With
  // a trainee the run is stored: the report returned is then the stored one — the fixed-step
  // replay of the recording (so it replays to the same state hash), with "record_id".
  // Throws InputError without a run launched since the last finish()/stop().
  nlohmann::json finish();
  // Starts a new live session on the last finished run's recording, every hand on its recorded
  // track ("track" devices: the replay steps exactly as the record's). Throws InputError when
  // nothing was finished yet.
  void replay_last();
  void stop();  // stops without a report (finish() then throws); idempotent

  // Render thread: the newest snapshot (nullptr before the first). Valid until the next call.
  const render::RenderSnapshot* newest_snapshot();

  // UI thread.
  TrainerState state() const;
  TrainerStatus status() const;
  // Moves the events that happened since the last call into `out` (appends). Returns how many.
  size_t poll_events(std::vector<TrainerEvent>& out);
  DesktopInput& desktop() { return *desktop_; }
  const TrainerConfig& config() const { return config_; }
  // The scenario the last finish() recorded (what replay_last runs), if any.
  const std::optional<Scenario>& last_recording() const { return last_recording_; }
  // The last finish()'s report.
  const nlohmann::json& last_report() const { return last_report_; }
  // Adds the haptic loop's period histogram (every tick since the last start, warm-up excluded)
  // to `into`: a procedure pools its steps' ticks (DurationHistogram::merge). Nothing before the
  // first start. UI thread (the loop may be running: approximate then, as status()).
  void merge_haptic_period_into(DurationHistogram& into) const;

  // Finished drills whose record could not be written (the database full, locked, read-only or
  // damaged: finish() then returns the report with "save_error" naming the database instead of
  // "record_id"). They are kept in memory, oldest first, until saved; nothing is dropped.
  size_t unsaved_count() const { return unsaved_.size(); }
  // Stores the unsaved drills again, oldest first, each with the time it really finished; returns
  // the new record ids. Throws InputError naming the database at the first that fails still:
  // those stored before it stay stored, the rest stay kept. The last report gains "record_id"
  // when its drill is stored.
  std::vector<int64_t> save_unsaved();
  // Moves `other`'s unsaved drills to the end of this session's (a new session for a new drill
  // keeps what the old one could not store).
  void take_unsaved_from(TrainerSession& other);
  // The last resort when the trainer closes with drills unsaved: each one's recording as a
  // scenario file in `dir` (created), which `phaco run FILE --record DB --trainee NAME` stores
  // later. Returns the files written; throws InputError naming a file it cannot write.
  std::vector<std::filesystem::path> write_unsaved(const std::filesystem::path& dir) const;

 private:
  void launch(const Scenario& scenario, const std::array<std::string, 2>& devices);
  void join();
  void after_frame(Scene& scene);
  void at_end(Scene& scene, const RealtimeRunReport* live);

  TrainerConfig config_;
  std::shared_ptr<DesktopInput> desktop_;
  TripleBuffer<render::RenderSnapshot> snapshots_;
  bool have_snapshot_ = false;  // render thread only
  bool unfinished_ = false;     // a run was launched and neither finished nor stopped

  // One live run: what start() made. launched_*: what reset() restarts (the config's drill, or
  // the replayed recording).
  std::optional<Scenario> launched_scenario_;
  std::array<std::string, 2> launched_devices_;
  Scenario running_scenario_;
  std::array<std::string, 2> running_devices_;
  std::unique_ptr<HapticSession> haptics_;
  std::array<std::unique_ptr<DeviceRecorder>, 2> recorders_;
  RecordingClock clock_;
  std::thread sim_;
  std::atomic<bool> stop_{false}, pause_{false};
  int64_t paused_at_ns_ = 0;  // UI thread

  // Simulation thread → UI thread.
  std::atomic<uint8_t> state_{static_cast<uint8_t>(TrainerState::Idle)};
  std::atomic<uint64_t> frame_{0}, snapshots_published_{0};
  std::atomic<double> sim_time_s_{0}, sim_rate_hz_{0};
  SpscRing<TrainerEvent, 256> events_;
  size_t events_seen_ = 0;    // simulation thread
  int64_t rate_t0_ns_ = 0;    // simulation thread
  uint64_t rate_frame0_ = 0;  // simulation thread
  // Written by the simulation thread before it exits; read by the UI thread after join().
  nlohmann::json end_report_;
  uint64_t end_frames_ = 0;
  std::string error_;
  std::atomic<bool> failed_{false};

  std::optional<Scenario> last_recording_;
  nlohmann::json last_report_;

  struct UnsavedRun {
    std::filesystem::path db;
    std::string trainee;
    Scenario recording;
    nlohmann::json report;  // the stored report: the replay's, with the live figures
    double run_s = 0;       // the live run's wall time, pauses left out
    double finished_s = 0;  // when it ended, s since the Unix epoch
    bool is_last = false;   // the drill last_report_ describes
  };
  std::vector<UnsavedRun> unsaved_;  // UI thread
};

}  // namespace phaco
