#include "engine/haptics/recording_device.hpp"

namespace phaco {

namespace {

// Forwards every call; what read() returns is also recorded (DeviceRecorder keeps new samples
// only, so repeated reads of one sample are one track sample), with the paused time taken out.
class RecordingDevice final : public Device {
 public:
  RecordingDevice(std::unique_ptr<Device> inner, DeviceRecorder& recorder,
                  const RecordingClock* clock)
      : inner_(std::move(inner)), recorder_(recorder), clock_(clock) {}
  std::string_view name() const override { return inner_->name(); }
  DeviceLimits limits() const override { return inner_->limits(); }
  void start(int64_t now_ns) override { inner_->start(now_ns); }
  void stop() override { inner_->stop(); }
  bool read(int64_t now_ns, DeviceSample& out) override {
    const bool got = inner_->read(now_ns, out);
    if (!got) return false;
    if (!clock_) {
      recorder_.record(out);
      return true;
    }
    // Relaxed: a flag and a total the UI thread sets; a sample recorded one tick late is harmless.
    if (!clock_->paused.load(std::memory_order_relaxed)) {
      DeviceSample s = out;
      s.t_ns -= clock_->paused_ns.load(std::memory_order_relaxed);
      recorder_.record(s);
    }
    return true;
  }
  void write_force(const Vec3& force_mn, int64_t now_ns) override {
    inner_->write_force(force_mn, now_ns);
  }
  DeviceHealth health(int64_t now_ns) const override { return inner_->health(now_ns); }
  DeviceCounters counters() const override { return inner_->counters(); }

 private:
  std::unique_ptr<Device> inner_;
  DeviceRecorder& recorder_;
  const RecordingClock* clock_;
};

}  // namespace

std::unique_ptr<Device> recording_device(std::unique_ptr<Device> inner, DeviceRecorder& recorder,
                                         const RecordingClock* clock) {
  return std::make_unique<RecordingDevice>(std::move(inner), recorder, clock);
}

}  // namespace phaco
