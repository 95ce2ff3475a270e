#pragma once
// A device that plays a scenario hand track (DESIGN.md §7): at haptic time now the pose is
// sample_track(track, (now − start) s) — linear in pos/grip/pedal, slerp in quat, exactly as the
// simulation samples scripted hands — so a scripted run through the haptic loop sees the same
// tool path as a run without it. Ended after the last sample + hold_s. Forces written are kept in
// a fixed ring (ForceLog) for tests and inspection. Reads nothing but its own track; allocates
// only at construction.
#include <atomic>
#include <cstdint>
#include <string>
#include <vector>

#include "engine/haptics/device.hpp"
#include "engine/io/scenario.hpp"

namespace phaco {

// Options shared with ReplayDevice (engine/haptics/device.hpp: TrackDeviceOptions).
using ScriptedDeviceOptions = TrackDeviceOptions;

class ScriptedDevice final : public Device {
 public:
  // Throws InputError when the track is empty.
  explicit ScriptedDevice(HandTrack track, ScriptedDeviceOptions options = {});

  std::string_view name() const override {
    // Both arms as views: a std::string arm would make the result view a temporary.
    return options_.name.empty() ? std::string_view("scripted") : std::string_view(options_.name);
  }
  DeviceLimits limits() const override { return options_.limits; }
  void start(int64_t now_ns) override;
  void stop() override { started_ = false; }
  // Before start(): false. seq counts reads from 1; t_ns = now.
  bool read(int64_t now_ns, DeviceSample& out) override;
  void write_force(const Vec3& force_mn, int64_t now_ns) override;
  // Silent before start, Ended once (now − start) > last sample time + hold_s, else Ok.
  DeviceHealth health(int64_t now_ns) const override;
  DeviceCounters counters() const override;

  const HandTrack& track() const { return track_; }
  const ForceLog& forces() const { return forces_; }

 private:
  HandTrack track_;
  ScriptedDeviceOptions options_;
  ForceLog forces_;
  int64_t start_ns_ = 0;
  int64_t end_ns_ = 0;  // start + last sample + hold
  bool started_ = false;
  uint32_t seq_ = 0;
  // Relaxed: a statistic read by other threads, ordering nothing.
  std::atomic<uint64_t> accepted_{0};
};

}  // namespace phaco
