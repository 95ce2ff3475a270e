#pragma once
// Recorded sessions (DESIGN.md §7: a recording is a scenario whose track came from a device).
//
// DeviceRecorder keeps the distinct samples read from any device (a new seq, a later time) in a
// buffer allocated up front, so recording on the haptic thread never allocates; beyond capacity
// samples are dropped and counted. It writes them as a scenario hand track: t = receive time −
// first sample's receive time, quat normalised, grip/pedal clamped to their ranges; a sample that
// fails the session's bounds (sample_bounds.hpp: non-finite, outside the workspace) is rejected
// and counted (what the scenario loader accepts, so a written recording loads back bit for bit).
// Buttons and seq are not part of the scenario format and are not recorded.
//
// ReplayDevice plays such a track exactly as recorded: sample-and-hold at the recorded times (no
// interpolation, unlike ScriptedDevice), seq = sample index + 1, t_ns = start + recorded time.
// Round trip: record → write → load_scenario → replay gives the recorded samples back exactly.
#include <atomic>
#include <cstdint>
#include <filesystem>
#include <span>
#include <string>
#include <vector>

#include "engine/haptics/device.hpp"
#include "engine/io/scenario.hpp"

namespace phaco {

class DeviceRecorder {
 public:
  explicit DeviceRecorder(std::size_t capacity);

  // Haptic-thread safe (no allocation, no lock). Keeps `s` when it is new: its seq differs from
  // the last kept sample's and its time is later. Returns true when kept.
  bool record(const DeviceSample& s) noexcept;

  std::size_t size() const { return samples_.size(); }
  std::size_t capacity() const { return capacity_; }
  uint64_t dropped() const { return dropped_; }     // new samples beyond capacity
  uint64_t rejected() const { return rejected_; }   // new samples failing bound_sample
  int64_t origin_ns() const { return origin_ns_; }  // receive time of t = 0
  std::span<const TrackSample> samples() const { return samples_; }

  // The recording as a hand track; throws InputError when nothing was recorded.
  HandTrack track(Hand hand, ToolKind tool) const;
  // `base` (drill, eye, dt, seed...) with the recorded hand added or replaced; duration_s is
  // raised to cover the recording (at least dt_s). Throws InputError when nothing was recorded.
  Scenario scenario(Scenario base, Hand hand, ToolKind tool) const;
  // scenario(...) written as JSON (engine/io to_json); throws InputError when it cannot write.
  void write(const std::filesystem::path& file, const Scenario& base, Hand hand,
             ToolKind tool) const;

 private:
  std::vector<TrackSample> samples_;  // reserved to capacity_ at construction
  std::size_t capacity_;
  int64_t origin_ns_ = 0;
  int64_t last_ns_ = 0;
  uint32_t last_seq_ = 0;
  bool seen_ = false;  // a sample was offered (last_seq_, last_ns_ are set)
  bool any_ = false;   // a sample was kept (origin_ns_ is set)
  uint64_t dropped_ = 0, rejected_ = 0;
};

using ReplayDeviceOptions = TrackDeviceOptions;

class ReplayDevice final : public Device {
 public:
  // Throws InputError when the track is empty.
  explicit ReplayDevice(HandTrack track, ReplayDeviceOptions options = {});

  std::string_view name() const override {
    return options_.name.empty() ? std::string_view("replay") : std::string_view(options_.name);
  }
  DeviceLimits limits() const override { return options_.limits; }
  void start(int64_t now_ns) override;
  void stop() override { started_ = false; }
  // The last sample with recorded time <= now − start; false before start or before the first.
  bool read(int64_t now_ns, DeviceSample& out) override;
  void write_force(const Vec3& force_mn, int64_t now_ns) override;
  // Silent before start, Ended once now − start > last sample time + hold_s, else Ok.
  DeviceHealth health(int64_t now_ns) const override;
  DeviceCounters counters() const override;

  const HandTrack& track() const { return track_; }
  const ForceLog& forces() const { return forces_; }

 private:
  HandTrack track_;
  std::vector<int64_t> t_ns_;  // recorded times in ns from the start, one per sample
  ReplayDeviceOptions options_;
  ForceLog forces_;
  int64_t start_ns_ = 0;
  bool started_ = false;
  std::size_t cursor_ = 0;  // last index played; playback normally only moves forward
  // Relaxed: a statistic read by other threads, ordering nothing.
  std::atomic<uint64_t> accepted_{0};
};

}  // namespace phaco
