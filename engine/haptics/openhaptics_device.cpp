#include "engine/haptics/openhaptics_device.hpp"

// UNTESTED: see the header. Written against the OpenHaptics 3.x HD API reference.
#if PHACO_HAVE_OPENHAPTICS
#include <HD/hd.h>

#include <algorithm>

#include "engine/core/error.hpp"
#endif

namespace phaco {

#if PHACO_HAVE_OPENHAPTICS

bool openhaptics_available() {
  return true;
}

OpenHapticsDevice::OpenHapticsDevice(OpenHapticsOptions options) : options_(std::move(options)) {
  name_ = "openhaptics" + (options_.device_name.empty() ? "" : ":" + options_.device_name);
  const HHD hhd =
      hdInitDevice(options_.device_name.empty() ? HD_DEFAULT_DEVICE : options_.device_name.c_str());
  const HDErrorInfo err = hdGetError();
  if (HD_DEVICE_ERROR(err)) {
    throw InputError(
        "openhaptics: cannot open device '" +
        (options_.device_name.empty() ? std::string("default") : options_.device_name) +
        "': " + hdGetErrorString(err.errorCode));
  }
  handle_ = hhd;
  hdMakeCurrentDevice(hhd);
  HDdouble max_force_n = 0, max_stiffness_n_per_mm = 0, max_damping = 0;
  HDdouble workspace[6] = {};
  hdGetDoublev(HD_NOMINAL_MAX_FORCE, &max_force_n);
  hdGetDoublev(HD_NOMINAL_MAX_STIFFNESS, &max_stiffness_n_per_mm);
  hdGetDoublev(HD_NOMINAL_MAX_DAMPING, &max_damping);
  hdGetDoublev(HD_USABLE_WORKSPACE_DIMENSIONS, workspace);  // minX minY minZ maxX maxY maxZ, mm
  limits_.max_force_mn = max_force_n * 1000.0;
  limits_.max_stiffness_mn_per_mm = max_stiffness_n_per_mm * 1000.0;
  limits_.max_damping_mn_s_per_mm = max_damping * 1000.0;
  const Vec3 a =
      options_.offset_mm + options_.scale * Vec3(workspace[0], workspace[1], workspace[2]);
  const Vec3 b =
      options_.offset_mm + options_.scale * Vec3(workspace[3], workspace[4], workspace[5]);
  limits_.workspace_min_mm = a.cwiseMin(b);
  limits_.workspace_max_mm = a.cwiseMax(b);
  limits_.has_force = max_force_n > 0;
}

OpenHapticsDevice::~OpenHapticsDevice() {
  stop();
  hdDisableDevice(handle_);
}

void OpenHapticsDevice::start(int64_t /*now_ns*/) {
  hdMakeCurrentDevice(handle_);
  hdEnable(HD_FORCE_OUTPUT);
  started_ = true;
}

void OpenHapticsDevice::stop() {
  if (!started_) return;
  hdMakeCurrentDevice(handle_);
  if (!in_frame_) hdBeginFrame(handle_);
  const HDdouble zero[3] = {0, 0, 0};
  hdSetDoublev(HD_CURRENT_FORCE, zero);
  hdEndFrame(handle_);
  in_frame_ = false;
  hdDisable(HD_FORCE_OUTPUT);
  started_ = false;
}

bool OpenHapticsDevice::read(int64_t now_ns, DeviceSample& out) {
  if (!started_ || failed_) {
    if (have_last_) out = last_;
    return have_last_;
  }
  if (in_frame_) hdEndFrame(handle_);  // write_force was not called last tick
  hdBeginFrame(handle_);
  in_frame_ = true;
  HDdouble m[16];  // column-major 4x4, translation in mm
  HDint buttons = 0;
  hdGetDoublev(HD_CURRENT_TRANSFORM, m);
  hdGetIntegerv(HD_CURRENT_BUTTONS, &buttons);
  if (HD_DEVICE_ERROR(hdGetError())) {
    failed_ = true;
    if (have_last_) out = last_;
    return have_last_;
  }
  Eigen::Matrix3d r;
  r << m[0], m[4], m[8], m[1], m[5], m[9], m[2], m[6], m[10];
  last_.t_ns = now_ns;
  last_.seq = ++seq_;
  last_.pos_mm = options_.offset_mm + options_.scale * Vec3(m[12], m[13], m[14]);
  last_.quat = Quat(r).normalized();
  last_.buttons = static_cast<uint32_t>(buttons);
  last_.grip = (buttons & HD_DEVICE_BUTTON_1) ? 1.0 : 0.0;  // stylus button 1 closes forceps
  last_.pedal = 0;
  have_last_ = true;
  out = last_;
  return true;
}

void OpenHapticsDevice::write_force(const Vec3& force_mn, int64_t now_ns) {
  if (!started_) return;
  if (!in_frame_) {
    hdBeginFrame(handle_);
    in_frame_ = true;
  }
  const bool ok = !failed_ && limits_.has_force;
  // Scene → device frame is the inverse of the pose map: only the scale's sign matters for a
  // direction, and forces are not scaled.
  const Vec3 f =
      ok ? Vec3(clamp_force(force_mn, limits_.max_force_mn) * (options_.scale < 0 ? -1.0 : 1.0))
         : Vec3::Zero();
  const HDdouble newtons[3] = {f.x() * 1e-3, f.y() * 1e-3, f.z() * 1e-3};
  hdSetDoublev(HD_CURRENT_FORCE, newtons);
  hdEndFrame(handle_);
  in_frame_ = false;
  if (HD_DEVICE_ERROR(hdGetError())) failed_ = true;
}

DeviceHealth OpenHapticsDevice::health(int64_t /*now_ns*/) const {
  if (failed_) return DeviceHealth::Failed;
  return started_ ? DeviceHealth::Ok : DeviceHealth::Silent;
}

#else

bool openhaptics_available() {
  return false;
}

#endif

}  // namespace phaco
