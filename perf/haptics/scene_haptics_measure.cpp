#include "perf/haptics/scene_haptics_measure.hpp"

#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <thread>

#include "engine/core/clock.hpp"
#include "engine/haptics/scripted_device.hpp"
#include "engine/haptics/udp_bridge.hpp"
#include "engine/io/track.hpp"
#include "perf/cores.hpp"
#include "procedures/haptics/realtime_run.hpp"
// The haptic-thread allocation counter the tests use (global operator new, per marked thread);
// linked into phaco-perf so the harness reports the same count.
#include "perf/haptics/counting_device.hpp"
#include "tests/engine/haptics/alloc_counter.hpp"

namespace phaco::perf {
namespace {

Scenario demo() {
  return load_scenario(std::filesystem::path(PHACO_SOURCE_DIR) /
                       "data/scenarios/capsulorhexis_demo.json");
}

// Sum of the "steal" column over all cores (/proc/stat first line), in ms; −1 where unreadable.
double steal_ms() {
  std::ifstream in("/proc/stat");
  std::string line;
  if (!std::getline(in, line)) return -1;
  std::istringstream words(line);
  std::string cpu;
  double v[8] = {};
  words >> cpu;
  for (double& x : v) words >> x;
  if (!words) return -1;
  return v[7] * 1000.0 / double(sysconf(_SC_CLK_TCK));
}

}  // namespace

std::vector<SceneHapticsRow> measure_scene_haptics(const std::vector<SceneHapticsCase>& cases) {
  const Scenario s = demo();
  std::vector<SceneHapticsRow> rows;
  for (const SceneHapticsCase& c : cases) {
    HapticSessionConfig config;
    config.loop.realtime = c.realtime;
    config.loop.lock_memory = c.realtime;
    config.min_model_interval_ms = c.model_interval_ms;
    const bool two_cores = std::thread::hardware_concurrency() >= 2;
    if (two_cores) config.loop.cpu = 1;
    HapticSession session(config);
    auto counting = std::make_unique<CountingDevice>(
        std::make_unique<ScriptedDevice>(*s.find_hand(Hand::Left)));
    CountingDevice* probe = counting.get();
    session.attach(Hand::Left, std::move(counting));

    // Count from the haptic thread's first read: run_realtime builds the scene and starts the
    // session; the thread's own start-up (stack, statistics) happens before its first tick.
    const bool countable = test::haptic_allocation_counting_available();
    if (countable) {
      test::open_allocation_window();
      probe->arm();
    }
    RealtimeRunOptions run;
    run.duration_s = c.seconds;
    run.stall_at_s = c.stall_at_s;
    run.stall_ms = c.stall_ms;
    const double steal_before = steal_ms();
    RealtimeRunReport r;
    {
      PinnedScope pin(two_cores ? 0 : -1);
      r = run_realtime(s, SceneOptions{}, session, run);
    }
    const double steal_after = steal_ms();
    if (countable) test::close_allocation_window();

    SceneHapticsRow row;
    row.c = c;
    const HapticSessionStats& h = r.haptics;
    row.fifo = h.realtime.fifo, row.memory_locked = h.realtime.memory_locked;
    row.realtime_detail = h.realtime.detail;
    row.ticks = double(h.loop.ticks), row.overruns = double(h.loop.overruns);
    row.missed = double(h.loop.missed_deadlines);
    row.period_p50_us = h.loop.period.p50_us, row.period_p99_us = h.loop.period.p99_us;
    row.period_p999_us = h.loop.period.p999_us, row.period_max_us = h.loop.period.max_us;
    row.late_p50_us = h.loop.lateness.p50_us, row.late_p99_us = h.loop.lateness.p99_us;
    row.late_max_us = h.loop.lateness.max_us;
    row.compute_p50_us = h.loop.compute.p50_us, row.compute_p99_us = h.loop.compute.p99_us;
    row.compute_max_us = h.loop.compute.max_us;
    const HapticHandStats& hand = h.hands[static_cast<size_t>(Hand::Left)];
    row.latency_p50_us = hand.latency.p50_us, row.latency_p99_us = hand.latency.p99_us;
    row.latency_max_us = hand.latency.max_us;
    row.allocations =
        countable && probe->marked() ? double(test::allocations_on_marked_threads()) : -1.0;
    row.max_force_mn = hand.max_force_mn, row.max_force_step_mn = hand.max_force_step_mn;
    row.models = double(hand.models_adopted), row.frames = double(r.frames);
    row.frame_p50_ms = r.frame_p50_ms, row.frame_p99_ms = r.frame_p99_ms;
    row.late_frames = double(r.late_frames);
    row.steal_ms = steal_before >= 0 && steal_after >= 0 ? steal_after - steal_before : -1;
    rows.push_back(row);
  }
  return rows;
}

UdpBridgeRow measure_udp_bridge(double seconds, double silence_timeout_ms) {
  const Scenario s = demo();
  const HandTrack& track = *s.find_hand(Hand::Left);
  UdpBridgePeer peer(0, "127.0.0.1");
  UdpBridgeConfig config;
  config.bind_host = "127.0.0.1";
  config.peer_host = "127.0.0.1";
  config.peer_port = peer.local_port();
  config.silence_timeout_ms = silence_timeout_ms;
  auto device = std::make_unique<UdpBridgeDevice>(config);
  UdpBridgeDevice* bridge = device.get();
  peer.set_device("127.0.0.1", bridge->local_port());

  HapticSessionConfig hc;  // real-time priority if the machine gives it, as in the trainer
  HapticSession session(hc);
  session.attach(Hand::Left, std::move(device));

  std::atomic<bool> sending{true}, receiving{true};
  std::atomic<uint64_t> sent{0};
  std::atomic<int64_t> last_send_us{0};
  std::vector<double> round_trips;
  round_trips.reserve(static_cast<size_t>(seconds * 1200));
  double forces = 0, silence_to_zero_ms = -1;

  // The peer: the forceps track at 1 kHz in real time (as a device driver in another process
  // would).
  std::thread sender([&] {
    const uint64_t t0 = steady_time_us();
    for (uint32_t seq = 1; sending.load(std::memory_order_relaxed); ++seq) {
      const uint64_t now = steady_time_us();
      const double t = double(now - t0) * 1e-6;
      const ToolPose p = sample_track(track.track, std::fmod(t, s.duration_s));
      udp_protocol::PoseMessage m;
      m.seq = seq;
      m.sender_time_us = now;
      m.pos_mm = {float(p.pos.x()), float(p.pos.y()), float(p.pos.z())};
      m.quat = {float(p.quat.w()), float(p.quat.x()), float(p.quat.y()), float(p.quat.z())};
      m.grip = float(p.grip), m.pedal = float(p.pedal);
      peer.send(m);
      sent.fetch_add(1, std::memory_order_relaxed);
      last_send_us.store(int64_t(now), std::memory_order_relaxed);
      std::this_thread::sleep_until(
          std::chrono::steady_clock::time_point(std::chrono::microseconds(t0 + 1000ull * seq)));
    }
  });
  std::thread receiver([&] {
    while (receiving.load(std::memory_order_relaxed)) {
      const auto f = peer.receive_force(20);
      if (!f) continue;
      const uint64_t now = steady_time_us();
      forces += 1;
      if (sending.load(std::memory_order_relaxed)) {
        if (f->ack_sender_time_us) round_trips.push_back(double(now - f->ack_sender_time_us));
      } else if (silence_to_zero_ms < 0 && f->health != 0 &&
                 f->force_mn == std::array<float, 3>{0, 0, 0}) {
        // From the last pose sent (issue 18: zero force within 5 ms of silence, timeout included).
        silence_to_zero_ms = (double(now) - double(last_send_us.load())) * 1e-3;
      }
    }
  });

  RealtimeRunOptions run;
  run.duration_s = seconds;
  std::thread stopper([&] {
    // The peer goes silent 0.5 s before the end; the session keeps running.
    std::this_thread::sleep_for(std::chrono::duration<double>(std::max(0.1, seconds - 0.5)));
    sending.store(false);
  });
  const RealtimeRunReport r = run_realtime(s, SceneOptions{}, session, run);
  stopper.join();
  sender.join();
  receiving.store(false);
  receiver.join();

  UdpBridgeRow row;
  row.seconds = seconds;
  row.sent = double(sent.load());
  const DeviceCounters& c = r.haptics.hands[static_cast<size_t>(Hand::Left)].counters;
  row.accepted = double(c.accepted);
  row.dropped = double(c.packets() - c.accepted);
  row.forces_received = forces;
  std::sort(round_trips.begin(), round_trips.end());
  auto q = [&](double p) {
    return round_trips.empty() ? 0.0
                               : round_trips[std::min(round_trips.size() - 1,
                                                      size_t(p * double(round_trips.size())))];
  };
  row.round_trip_p50_us = q(0.5), row.round_trip_p99_us = q(0.99);
  row.round_trip_max_us = round_trips.empty() ? 0 : round_trips.back();
  row.silence_timeout_ms = silence_timeout_ms;
  row.silence_to_zero_ms = silence_to_zero_ms;
  return row;
}

}  // namespace phaco::perf
