#pragma once
// OpenHaptics (3D Systems HD API) backend for Phantom / Touch devices, as seed 003 drives its
// Phantom. Compiled only when the SDK is found (PHACO_HAVE_OPENHAPTICS, set by CMake when HD/hd.h
// and libHD exist). UNTESTED HERE: the SDK and a device are not on the development machine; this
// file has never been compiled with PHACO_HAVE_OPENHAPTICS=1.
//
// Our own 1 kHz loop ticks, so OpenHaptics' servo scheduler callbacks are not used: read() opens
// an HD frame (hdBeginFrame) and reads the pose, write_force() sets HD_CURRENT_FORCE and closes it
// (hdEndFrame, which commits the force). Should the HD runtime not refresh device state without
// its scheduler running, the fallback is hdStartScheduler with an asynchronous callback copying
// state through a seqlock, like the UDP bridge. Units: HD positions are mm (kept), forces N (our
// mN / 1000). Frame: the device's (+y up, +z toward the user), mapped to the scene by
// scene = offset_mm + scale · device.
#include <string>

#include "engine/haptics/device.hpp"

namespace phaco {

// True when this build has the OpenHaptics backend.
bool openhaptics_available();

struct OpenHapticsOptions {
  std::string device_name;  // empty: HD_DEFAULT_DEVICE
  Vec3 offset_mm = Vec3::Zero();
  double scale = 1.0;  // scene mm per device mm
};

#if PHACO_HAVE_OPENHAPTICS
class OpenHapticsDevice final : public Device {
 public:
  // hdInitDevice; throws InputError naming the HD error when the device cannot be opened.
  explicit OpenHapticsDevice(OpenHapticsOptions options = {});
  ~OpenHapticsDevice() override;

  std::string_view name() const override { return name_; }
  DeviceLimits limits() const override { return limits_; }
  void start(int64_t now_ns) override;  // enables force output
  void stop() override;                 // zero force, disables force output
  bool read(int64_t now_ns, DeviceSample& out) override;
  void write_force(const Vec3& force_mn, int64_t now_ns) override;
  DeviceHealth health(int64_t now_ns) const override;

 private:
  OpenHapticsOptions options_;
  std::string name_;
  DeviceLimits limits_{};
  unsigned int handle_ = 0;  // HHD
  bool in_frame_ = false;
  bool failed_ = false;
  bool started_ = false;
  uint32_t seq_ = 0;
  DeviceSample last_{};
  bool have_last_ = false;
};
#endif

}  // namespace phaco
