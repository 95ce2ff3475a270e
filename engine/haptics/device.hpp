#pragma once
// One interface for every haptic/tracking device (issue 6 item 4; DESIGN.md §5): a 6-DOF pose,
// grip, foot pedal, buttons, a force output and the device's limits. The 1 kHz haptic thread calls
// read / write_force / health once per tick per device: one virtual call per device per tick,
// never per element. Backends: scripted (a scenario track), replay (a recording), UDP bridge
// (another process or machine, as seed 001 links two machines), OpenHaptics (when the SDK is
// found). Units: mm, mN, s (DESIGN.md §6); times are steady-clock ns (engine/core/clock.hpp).
//
// Failure rule shared by every backend: when health is Silent or Failed, read() keeps returning
// the last good pose (the tool freezes where it was) and write_force sends/keeps zero force.
#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "engine/core/math.hpp"
#include "engine/core/workspace.hpp"
#include "engine/io/track.hpp"

namespace phaco {

struct DeviceLimits {
  double max_force_mn = 3300;             // mN, peak force the device can render
  double max_stiffness_mn_per_mm = 1000;  // mN/mm, stiffest spring it renders stably
  double max_damping_mn_s_per_mm = 2;     // mN·s/mm
  Vec3 workspace_min_mm = Vec3::Constant(-kWorkspaceHalfMm);  // mm, box the pose stays in
  Vec3 workspace_max_mm = Vec3::Constant(kWorkspaceHalfMm);   // mm (device frame)
  bool has_force = true;  // false: a tracker only, forces are ignored
};

struct DeviceSample {
  int64_t t_ns = 0;  // ns, steady clock, when this sample was received (or generated)
  uint32_t seq = 0;  // increases by one per new sample (wraps); the same seq = the same sample
  Vec3 pos_mm = Vec3::Zero();    // mm, tool tip
  Quat quat = Quat::Identity();  // unit; tool shaft = local +z rotated by quat
  double grip = 0;               // 0 open .. 1 closed
  double pedal = 0;              // 0..3 phaco foot pedal
  uint32_t buttons = 0;          // bit i = button i pressed
};

// A new sample at `t_ns` holding a tool pose (no buttons): what devices that compute poses (a
// scripted track, the desktop's mouse and gamepad) hand to the loop.
inline DeviceSample sample_of(const ToolPose& p, int64_t t_ns, uint32_t seq) {
  DeviceSample s;
  s.t_ns = t_ns, s.seq = seq;
  s.pos_mm = p.pos, s.quat = p.quat, s.grip = p.grip, s.pedal = p.pedal;
  return s;
}

enum class DeviceHealth : uint8_t {
  Ok = 0,
  Silent = 1,  // no data for longer than the device's timeout (or none yet): tool frozen, force 0
  Ended = 2,   // a finite script/replay ran out (the last pose is held)
  Failed = 3,  // the device or its I/O thread failed: tool frozen, force 0
};
std::string_view to_string(DeviceHealth health);

// What a device accepted and why it dropped the rest. Only the UDP bridge fills most of these.
struct DeviceCounters {
  uint64_t accepted = 0;          // samples taken
  uint64_t malformed = 0;         // wrong size, wrong magic, unknown type
  uint64_t bad_checksum = 0;      // CRC-32 mismatch
  uint64_t wrong_version = 0;     // protocol version we do not speak
  uint64_t wrong_peer = 0;        // from another address:port, or another device id
  uint64_t non_finite = 0;        // a NaN or infinite number, or a zero quaternion
  uint64_t out_of_workspace = 0;  // a position beyond ±kWorkspaceHalfMm (sample_bounds.hpp)
  uint64_t duplicate = 0;         // seq equal to the newest accepted
  uint64_t out_of_order = 0;      // seq behind the newest accepted (wrap-around aware)
  uint64_t stale = 0;             // too old on arrival (see docs/udp_bridge_protocol.md)
  uint64_t clamped = 0;   // accepted with grip or pedal clamped into range (also in accepted)
  uint64_t silences = 0;  // times the haptic thread saw the device go silent
  // Every packet seen, each in exactly one of the counters above except clamped and silences.
  uint64_t packets() const {
    return accepted + malformed + bad_checksum + wrong_version + wrong_peer + non_finite +
           out_of_workspace + duplicate + out_of_order + stale;
  }
  uint64_t dropped() const { return packets() - accepted; }
};

// Options of the devices that play a scenario track (scripted: interpolated; replay: as recorded).
struct TrackDeviceOptions {
  std::string name;                   // shown in reports; empty: the device's kind
  DeviceLimits limits{};              // has_force: the loop computes and records forces
  double hold_s = 0;                  // s, the last pose is held this long before Ended
  std::size_t force_log_size = 4096;  // forces kept (the last N)
};

class Device {
 public:
  virtual ~Device();
  virtual std::string_view name() const = 0;
  virtual DeviceLimits limits() const = 0;
  // Start-up and shut-down, outside the haptic loop: they may allocate, spawn threads, throw.
  // `now_ns` is the steady clock at start: scripted and replay devices play from it.
  virtual void start(int64_t now_ns) = 0;
  virtual void stop() = 0;

  // Called by the 1 kHz haptic thread every tick: must not allocate, lock, block, or make a
  // system call other than reading the clock.
  // The newest sample in `out`; false when there is none yet (out is then left unchanged).
  virtual bool read(int64_t now_ns, DeviceSample& out) = 0;
  // The force to render (mN, scene frame); a device that is not Ok renders zero instead.
  virtual void write_force(const Vec3& force_mn, int64_t now_ns) = 0;
  virtual DeviceHealth health(int64_t now_ns) const = 0;
  // Safe to call from any thread.
  virtual DeviceCounters counters() const;
};

// The last N forces written to a device, for tests and inspection. Fixed capacity, allocated at
// construction, so push() on the haptic thread never allocates. Not synchronised: read it from the
// haptic thread or after stop().
struct ForceRecord {
  int64_t t_ns = 0;              // ns, steady clock, as given to write_force
  Vec3 force_mn = Vec3::Zero();  // mN
};
class ForceLog {
 public:
  explicit ForceLog(std::size_t capacity);
  void push(const ForceRecord& r) noexcept;
  std::size_t capacity() const { return ring_.size(); }
  uint64_t total() const { return total_; }  // all ever pushed
  // Oldest first, at most capacity() of them.
  std::vector<ForceRecord> recent() const;
  // The newest, or a zero record when nothing was pushed.
  ForceRecord last() const;

 private:
  std::vector<ForceRecord> ring_;
  uint64_t total_ = 0;
};

// `force` with its magnitude clamped to `max_mn`; a non-finite force becomes zero (a NaN must
// never reach a motor).
Vec3 clamp_force(const Vec3& force_mn, double max_mn);

}  // namespace phaco
