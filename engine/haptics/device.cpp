#include "engine/haptics/device.hpp"

#include <algorithm>
#include <cmath>

namespace phaco {

std::string_view to_string(DeviceHealth health) {
  switch (health) {
    case DeviceHealth::Ok:
      return "ok";
    case DeviceHealth::Silent:
      return "silent";
    case DeviceHealth::Ended:
      return "ended";
    case DeviceHealth::Failed:
      return "failed";
  }
  return "unknown";
}

Device::~Device() = default;

DeviceCounters Device::counters() const {
  return {};
}

ForceLog::ForceLog(std::size_t capacity) : ring_(std::max<std::size_t>(capacity, 1)) {}

void ForceLog::push(const ForceRecord& r) noexcept {
  ring_[total_ % ring_.size()] = r;
  ++total_;
}

std::vector<ForceRecord> ForceLog::recent() const {
  const std::size_t n = static_cast<std::size_t>(std::min<uint64_t>(total_, ring_.size()));
  std::vector<ForceRecord> out;
  out.reserve(n);
  for (uint64_t i = total_ - n; i < total_; ++i) out.push_back(ring_[i % ring_.size()]);
  return out;
}

ForceRecord ForceLog::last() const {
  return total_ == 0 ? ForceRecord{} : ring_[(total_ - 1) % ring_.size()];
}

Vec3 clamp_force(const Vec3& force_mn, double max_mn) {
  if (!force_mn.allFinite()) return Vec3::Zero();
  const double magnitude = force_mn.norm();
  if (!(max_mn > 0)) return Vec3::Zero();
  return magnitude > max_mn ? Vec3(force_mn * (max_mn / magnitude)) : force_mn;
}

}  // namespace phaco
