#pragma once
// The haptic runtime (DESIGN.md §5, issue 6): one 1 kHz thread (engine/haptics/haptic_loop) that,
// every tick and for each hand with a device,
//
//   reads the device's newest sample, checks its bounds (engine/haptics/sample_bounds.hpp: a
//     non-finite or out-of-workspace sample is dropped and counted, grip/pedal clamped)
//     ──▶ SPSC ring ──▶ the simulation drains it (newest_pose)
//   takes the newest local model, if one was published (triple buffer, acquire)
//   computes the force from it alone (systems/haptic_model: proxy, local nodes, grasp, lens, and
//   the port, against the device's own shaft)
//   writes the force to the device, zero when the device is silent or failed (its tool frozen)
//
// and never waits for the simulation: a stalled simulation leaves the last model running. The
// simulation side is a HapticPort (procedures/scene/haptic_port.hpp): `phaco run --haptics`, the
// trainer and the perf harness give a session to the scene.
//
// Nothing on the haptic path allocates, locks or makes a system call other than reading the
// clock (the devices promise the same for read/write_force/health); the per-hand state (≈ 260
// KiB) is allocated at construction.
#include <array>
#include <atomic>
#include <cstdint>
#include <memory>

#include "components/haptic_model.hpp"
#include "engine/haptics/device.hpp"
#include "engine/haptics/haptic_loop.hpp"
#include "engine/haptics/loop_stats.hpp"
#include "engine/haptics/spsc_ring.hpp"
#include "engine/haptics/triple_buffer.hpp"
#include "procedures/scene/haptic_port.hpp"
#include "systems/haptic_model/haptic_model.hpp"

namespace phaco {

struct HapticSessionConfig {
  LoopSettings loop;
  haptic_model::HapticSettings model;
  // The device velocity (for the coupling's damping) is the finite difference of new samples,
  // low-passed at this cut-off.
  double velocity_cutoff_hz = 100.0;
  // Models reach the haptic thread at most this often (0: every frame). A slow machine can spare
  // the copy; the harness uses it to show continuity with models at 30 Hz.
  double min_model_interval_ms = 0;
};

// Per hand, over the session (read with stats(); figures are snapshots while running).
struct HapticHandStats {
  bool attached = false;
  DeviceHealth health = DeviceHealth::Silent;
  DeviceCounters counters;
  uint64_t ticks = 0;            // ticks with this device
  uint64_t samples = 0;          // new samples taken (seq changed) within the bounds
  uint64_t samples_dropped = 0;  // ring full (the simulation did not drain it)
  // New samples that failed the bounds (sample_bounds.hpp), whatever the device: dropped before
  // the physics (the tool stays where the last good sample left it), or kept with grip/pedal
  // clamped.
  uint64_t samples_non_finite = 0, samples_outside_workspace = 0, samples_clamped = 0;
  uint64_t zero_force_ticks = 0;  // ticks the device was silent or failed: force zero, tool frozen
  uint64_t models_adopted = 0, clamped_ticks = 0, rejected_inputs = 0;
  double max_force_mn = 0;       // largest force sent
  double max_force_step_mn = 0;  // largest change between two consecutive ticks
  DurationSummary latency;       // device sample received → the force computed from it written
};

struct HapticSessionStats {
  RealtimeStatus realtime;
  LoopStatsSnapshot loop;
  int64_t spin_margin_ns = 0;  // the loop's learned spin margin (HapticLoop::spin_margin_ns)
  std::array<HapticHandStats, kHapticTools> hands;
  uint64_t models_published = 0;
};

class HapticSession final : public HapticPort {
 public:
  explicit HapticSession(const HapticSessionConfig& config = {});
  ~HapticSession() override;  // stops
  HapticSession(const HapticSession&) = delete;
  HapticSession& operator=(const HapticSession&) = delete;

  // Thread-safety (issue 22), on every public method as "Thread:". The owner (the thread that
  // builds the session: the simulation's) attaches, starts and stops; the HapticPort calls come
  // from the simulation thread once per frame; the tick runs on the 1 kHz thread.

  // Before start(): a device drives `hand`'s tool and receives its force (std::logic_error while
  // running). Thread: the owner.
  void attach(Hand hand, std::unique_ptr<Device> device);
  // Thread: any (devices change only before start()).
  Device* device(Hand hand) const { return hands_[index(hand)].device.get(); }

  void start();  // starts the devices, then the 1 kHz thread. Thread: the owner.
  void stop();   // stops the thread, then the devices; idempotent. Thread: the owner.
  // Thread: the owner.
  bool running() const { return loop_.running(); }

  // Thread: any, also while running (relaxed counters: approximate then, exact after stop()).
  HapticSessionStats stats() const;
  // One tick on the calling thread at the caller's time (info.wake_ns is "now" for the devices),
  // instead of the 1 kHz thread: deterministic tests of what a tick does at a given instant (the
  // silence bound). Only while the session is not running; throws std::logic_error otherwise.
  // Thread: the owner.
  void step(const TickInfo& info);

  // The 1 kHz thread's period histogram (occupied bins), for the harness's charts. Thread: any.
  std::vector<DurationHistogram::Bin> period_bins() const { return loop_.period_bins(); }
  // The same histogram whole, to pool over sessions (the trainer's procedure steps). Thread: any.
  const DurationHistogram& period_histogram() const { return loop_.period_histogram(); }

  // HapticPort. Thread: the simulation thread only (the ring's consumer, the triple buffer's
  // producer), concurrently with the 1 kHz thread.
  bool drives(Hand hand) const override { return hands_[index(hand)].device != nullptr; }
  bool newest_pose(Hand hand, ToolPose& pose) override;
  HapticModel& model_slot() override { return models_.write_slot(); }
  void publish_model() override;

  // The haptic thread's view, for tests and the harness: the last force sent per hand.
  // Thread: any (relaxed atomics: each component is the newest, the three may straddle a tick).
  Vec3 last_force(Hand hand) const;

 private:
  static constexpr std::size_t kRingCapacity = 1024;  // ≈ 1 s of samples at 1 kHz
  static size_t index(Hand hand) { return static_cast<size_t>(hand) % kHapticTools; }
  static void tick_entry(void* self, const TickInfo& info);
  void tick(const TickInfo& info);

  // A device sample as plain numbers: what crosses the ring (Eigen types are not nothrow-copyable
  // by the standard's traits, though they are in fact).
  struct RingSample {
    double pos[3];
    double quat[4];  // w, x, y, z
    double grip, pedal;
  };

  struct HandRuntime {
    std::unique_ptr<Device> device;
    std::unique_ptr<haptic_model::HapticToolState> state;
    std::unique_ptr<SpscRing<RingSample, kRingCapacity>> ring;
    // Haptic thread only.
    DeviceSample sample;
    bool have_sample = false;  // a sample passed the bounds: `sample` holds the newest such
    bool read_any = false;     // the device gave a sample (good or not): last_seq is its seq
    uint32_t last_seq = 0;
    int64_t last_sample_ns = 0;
    Vec3 last_pos = Vec3::Zero(), velocity = Vec3::Zero();
    Vec3 force = Vec3::Zero();
    DurationHistogram latency;
    // Written by the haptic thread, read by stats() (relaxed: figures, not synchronisation).
    std::atomic<uint64_t> ticks{0}, samples{0}, zero_force_ticks{0}, adopted{0}, clamped{0},
        rejected{0}, non_finite{0}, outside_workspace{0}, samples_clamped{0};
    std::atomic<double> max_force_mn{0}, max_force_step_mn{0};
    std::atomic<float> force_x{0}, force_y{0}, force_z{0};
    // Simulation thread only.
    ToolPose pose;
    bool pose_valid = false;
  };

  HapticSessionConfig config_;
  HapticLoop loop_;
  TripleBuffer<HapticModel> models_;
  std::array<HandRuntime, kHapticTools> hands_;
  std::atomic<uint64_t> published_{0};
  int64_t last_publish_ns_ = 0;  // simulation thread only
};

}  // namespace phaco
