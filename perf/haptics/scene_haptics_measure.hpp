#pragma once
// The haptic thread beside the running simulation (issue 6 "Rates", "Continuity", "Latency",
// "UDP bridge"): the default capsulorhexis scene stepped in real time on one core while the 1 kHz
// thread renders the forceps hand from a scripted device (the scene's own track) on the other.
// Plain rows; the `phaco-perf haptics` study prints and charts them.
#include <cstdint>
#include <string>
#include <vector>

namespace phaco::perf {

struct SceneHapticsCase {
  std::string label;
  double seconds = 60;
  bool realtime = true;                  // ask for SCHED_FIFO + mlockall
  double model_interval_ms = 0;          // models at most this often (0 = every frame, 120 Hz)
  double stall_at_s = -1, stall_ms = 0;  // one simulation stall
};

struct SceneHapticsRow {
  SceneHapticsCase c;
  bool fifo = false, memory_locked = false;
  std::string realtime_detail;
  double ticks = 0, overruns = 0, missed = 0;
  double period_p50_us = 0, period_p99_us = 0, period_p999_us = 0, period_max_us = 0;
  double late_p50_us = 0, late_p99_us = 0, late_max_us = 0;
  double compute_p50_us = 0, compute_p99_us = 0, compute_max_us = 0;
  double latency_p50_us = 0, latency_p99_us = 0, latency_max_us = 0;  // sample → its force written
  double allocations = -1;  // on the haptic thread after start-up; −1: not countable (sanitizer)
  double max_force_mn = 0, max_force_step_mn = 0;
  double models = 0, frames = 0, frame_p50_ms = 0, frame_p99_ms = 0, late_frames = 0;
  // CPU time the hypervisor took from this virtual machine's cores during the case (/proc/stat
  // "steal", summed over the cores); a SCHED_FIFO thread cannot run while its core is stolen.
  double steal_ms = 0;
};

// Runs each case (the demo's left hand, the forceps, on the device; the scene loops when the
// 40 s scenario ends before `seconds`). The haptic thread is pinned to CPU 1 and the simulation
// (the calling thread, one worker) to CPU 0, as the issue asks ("on the other core"), when the
// machine has two cores.
std::vector<SceneHapticsRow> measure_scene_haptics(const std::vector<SceneHapticsCase>& cases);

// The UDP bridge on loopback beside the same scene: a peer process-alike thread sends the forceps
// track at 1 kHz and reads the force packets back.
struct UdpBridgeRow {
  double seconds = 0;
  double sent = 0, accepted = 0, dropped = 0, forces_received = 0;
  double round_trip_p50_us = 0, round_trip_p99_us = 0,
         round_trip_max_us = 0;  // pose sent → its force back
  double silence_timeout_ms = 0;
  double silence_to_zero_ms = 0;  // the last pose sent → the first zero force the peer receives
};
// 3 ms: UdpBridgeConfig's default silence timeout.
UdpBridgeRow measure_udp_bridge(double seconds, double silence_timeout_ms = 3);

}  // namespace phaco::perf
