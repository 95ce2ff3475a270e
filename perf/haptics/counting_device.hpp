#pragma once
// A device wrapper for the harness: the first read after arm() marks the calling thread (the
// haptic thread) so that its allocations from then on are counted by the tests' allocation
// counter (tests/engine/haptics/alloc_counter, linked into phaco-perf). Everything else is passed
// through to the wrapped device.
#include <atomic>
#include <memory>
#include <string_view>

#include "engine/haptics/device.hpp"
#include "tests/engine/haptics/alloc_counter.hpp"

namespace phaco::perf {

class CountingDevice final : public Device {
 public:
  explicit CountingDevice(std::unique_ptr<Device> inner) : inner_(std::move(inner)) {}
  std::string_view name() const override { return inner_->name(); }
  DeviceLimits limits() const override { return inner_->limits(); }
  void start(int64_t now) override { inner_->start(now); }
  void stop() override { inner_->stop(); }
  bool read(int64_t now, DeviceSample& out) override {
    if (armed_.load(std::memory_order_relaxed)) {
      test::count_allocations_on_this_thread(true);
      armed_.store(false, std::memory_order_relaxed);
      marked_.store(true, std::memory_order_release);
    }
    return inner_->read(now, out);
  }
  void write_force(const Vec3& f, int64_t now) override { inner_->write_force(f, now); }
  DeviceHealth health(int64_t now) const override { return inner_->health(now); }
  DeviceCounters counters() const override { return inner_->counters(); }
  void arm() { armed_.store(true, std::memory_order_relaxed); }
  bool marked() const { return marked_.load(std::memory_order_acquire); }

 private:
  std::unique_ptr<Device> inner_;
  std::atomic<bool> armed_{false}, marked_{false};
};

}  // namespace phaco::perf
