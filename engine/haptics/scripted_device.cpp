#include "engine/haptics/scripted_device.hpp"

#include <cmath>

#include "engine/core/error.hpp"
#include "engine/io/track.hpp"

namespace phaco {

ScriptedDevice::ScriptedDevice(HandTrack track, ScriptedDeviceOptions options)
    : track_(std::move(track)), options_(std::move(options)), forces_(options_.force_log_size) {
  if (track_.track.empty()) {
    throw InputError("scripted device: the " + std::string(to_string(track_.hand)) +
                     " hand's track is empty; expected at least one sample");
  }
}

void ScriptedDevice::start(int64_t now_ns) {
  start_ns_ = now_ns;
  end_ns_ = now_ns + std::llround((track_.track.back().t + options_.hold_s) * 1e9);
  started_ = true;
}

bool ScriptedDevice::read(int64_t now_ns, DeviceSample& out) {
  if (!started_) return false;
  const ToolPose p = sample_track(track_.track, static_cast<double>(now_ns - start_ns_) * 1e-9);
  out = sample_of(p, now_ns, ++seq_);
  accepted_.fetch_add(1, std::memory_order_relaxed);  // relaxed: a statistic only
  return true;
}

void ScriptedDevice::write_force(const Vec3& force_mn, int64_t now_ns) {
  // Kept as given (not clamped): tests check what the loop asked for.
  forces_.push({now_ns, force_mn});
}

DeviceCounters ScriptedDevice::counters() const {
  DeviceCounters c;
  c.accepted = accepted_.load(std::memory_order_relaxed);
  return c;
}

DeviceHealth ScriptedDevice::health(int64_t now_ns) const {
  if (!started_) return DeviceHealth::Silent;
  return now_ns > end_ns_ ? DeviceHealth::Ended : DeviceHealth::Ok;
}

}  // namespace phaco
