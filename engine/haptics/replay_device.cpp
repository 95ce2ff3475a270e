#include "engine/haptics/replay_device.hpp"

#include <algorithm>
#include <cmath>
#include <fstream>

#include "engine/core/error.hpp"
#include "engine/haptics/sample_bounds.hpp"

namespace phaco {

DeviceRecorder::DeviceRecorder(std::size_t capacity) : capacity_(capacity) {
  samples_.reserve(capacity_);
}

bool DeviceRecorder::record(const DeviceSample& s) noexcept {
  if (seen_ && (s.seq == last_seq_ || s.t_ns <= last_ns_)) return false;  // seen already
  // A rejected sample is seen too: read again on the next tick, it is not counted again.
  seen_ = true;
  last_seq_ = s.seq;
  last_ns_ = s.t_ns;
  // The session's bounds (sample_bounds.hpp): a recording never holds what the physics would not
  // take, and always loads back (the scenario loader checks the same ranges).
  DeviceSample b = s;
  if (!keeps(bound_sample(b))) {
    ++rejected_;
    return false;
  }
  if (!any_) origin_ns_ = s.t_ns;
  any_ = true;
  if (samples_.size() >= capacity_) {
    ++dropped_;
    return false;
  }
  TrackSample x;
  x.t = static_cast<double>(s.t_ns - origin_ns_) * 1e-9;
  x.pos = b.pos_mm;
  x.quat = b.quat.normalized();
  x.grip = b.grip;
  x.pedal = b.pedal;
  samples_.push_back(x);  // within the reserved capacity: no allocation
  return true;
}

HandTrack DeviceRecorder::track(Hand hand, ToolKind tool) const {
  if (samples_.empty()) {
    throw InputError("device recording: no samples were recorded; nothing to write");
  }
  HandTrack h;
  h.hand = hand;
  h.tool = tool;
  h.track.assign(samples_.begin(), samples_.end());
  return h;
}

Scenario DeviceRecorder::scenario(Scenario base, Hand hand, ToolKind tool) const {
  HandTrack h = track(hand, tool);
  base.duration_s = std::max({base.duration_s, h.track.back().t, base.dt_s});
  auto it = std::find_if(base.hands.begin(), base.hands.end(),
                         [&](const HandTrack& x) { return x.hand == hand; });
  if (it != base.hands.end()) {
    *it = std::move(h);
  } else {
    base.hands.push_back(std::move(h));
    // Left first, as the loader orders hands.
    std::sort(base.hands.begin(), base.hands.end(),
              [](const HandTrack& a, const HandTrack& b) { return a.hand < b.hand; });
  }
  return base;
}

void DeviceRecorder::write(const std::filesystem::path& file, const Scenario& base, Hand hand,
                           ToolKind tool) const {
  const std::string text = to_json(scenario(base, hand, tool)).dump(2) + "\n";
  std::ofstream out(file, std::ios::binary | std::ios::trunc);
  if (!out) throw InputError(file.string() + ": cannot open for writing the device recording");
  out << text;
  out.close();
  if (!out) throw InputError(file.string() + ": write error while saving the device recording");
}

ReplayDevice::ReplayDevice(HandTrack track, ReplayDeviceOptions options)
    : track_(std::move(track)), options_(std::move(options)), forces_(options_.force_log_size) {
  if (track_.track.empty()) {
    throw InputError("replay device: the " + std::string(to_string(track_.hand)) +
                     " hand's recording is empty; expected at least one sample");
  }
  t_ns_.reserve(track_.track.size());
  // The recorder wrote t = ns * 1e-9; llround(t * 1e9) gives those ns back exactly (t < 2^53 ns).
  for (const TrackSample& s : track_.track) t_ns_.push_back(std::llround(s.t * 1e9));
}

void ReplayDevice::start(int64_t now_ns) {
  start_ns_ = now_ns;
  cursor_ = 0;
  started_ = true;
}

bool ReplayDevice::read(int64_t now_ns, DeviceSample& out) {
  if (!started_) return false;
  const int64_t elapsed = now_ns - start_ns_;
  if (elapsed < t_ns_.front()) return false;
  // Playback moves forward a sample or so per tick: step the cursor; search only if time went
  // backwards (a restart), so a tick is O(1) and never O(n).
  if (t_ns_[cursor_] > elapsed) {
    cursor_ = static_cast<std::size_t>(std::upper_bound(t_ns_.begin(), t_ns_.end(), elapsed) -
                                       t_ns_.begin() - 1);
  }
  while (cursor_ + 1 < t_ns_.size() && t_ns_[cursor_ + 1] <= elapsed) ++cursor_;
  const TrackSample& s = track_.track[cursor_];
  out.t_ns = start_ns_ + t_ns_[cursor_];
  out.seq = static_cast<uint32_t>(cursor_ + 1);
  out.pos_mm = s.pos;
  out.quat = s.quat;
  out.grip = s.grip;
  out.pedal = s.pedal;
  out.buttons = 0;
  accepted_.fetch_add(1, std::memory_order_relaxed);  // relaxed: a statistic only
  return true;
}

void ReplayDevice::write_force(const Vec3& force_mn, int64_t now_ns) {
  forces_.push({now_ns, force_mn});  // kept as given, for inspection
}

DeviceHealth ReplayDevice::health(int64_t now_ns) const {
  if (!started_) return DeviceHealth::Silent;
  const int64_t end = t_ns_.back() + std::llround(options_.hold_s * 1e9);
  return now_ns - start_ns_ > end ? DeviceHealth::Ended : DeviceHealth::Ok;
}

DeviceCounters ReplayDevice::counters() const {
  DeviceCounters c;
  c.accepted = accepted_.load(std::memory_order_relaxed);
  return c;
}

}  // namespace phaco
