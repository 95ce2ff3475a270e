#pragma once
// The bounds a device sample must meet before it may reach the physics (issue 18 item 1), the one
// check every device kind goes through: the haptic session applies it to each new sample it reads
// (UDP, replay, scripted, recording passthrough, OpenHaptics alike), the UDP bridge to each packet
// and the recorder to each sample it keeps.
//
//   position   finite, within ±kWorkspaceHalfMm of the eye's origin per axis  else DROPPED
//   rotation   finite quaternion, norm > 1e-6 (renormalised when not unit)    else DROPPED
//   grip       finite, clamped to [0, kMaxGrip]                               (non-finite: DROPPED)
//   pedal      finite, clamped to [0, kMaxPedal]                              (non-finite: DROPPED)
//
// Why drop the pose but clamp grip and pedal: a position outside the workspace says nothing about
// where the hand is (1e19 mm is a corrupt number, not a hand just past a wall), and clamping it
// would teleport the tool onto the workspace's face, through the eye, in one tick; dropping keeps
// the tool where the last good sample left it — the same freeze every device already does when
// it goes silent. Grip and pedal are controls that saturate: a pedal reported at 3.2 is a pedal
// pressed to the floor, and clamping keeps the rest of the sample (its pose is good). A
// non-finite grip or pedal is corruption, like a non-finite position, and drops the sample.
// The ranges are the scenario loader's (engine/io/scenario.cpp), so a recorded sample always
// loads back.
#include <cstdint>

#include "engine/core/workspace.hpp"
#include "engine/haptics/device.hpp"

namespace phaco {

inline constexpr double kMaxGrip = 1.0;   // 0 open .. 1 closed
inline constexpr double kMaxPedal = 3.0;  // phaco foot pedal positions 0..3

enum class SampleCheck : uint8_t {
  Ok,                // within every bound, untouched
  Clamped,           // grip or pedal was out of range and has been clamped; keep the sample
  NonFinite,         // a NaN or infinite number, or a zero quaternion: drop the sample
  OutsideWorkspace,  // a position beyond ±kWorkspaceHalfMm: drop the sample
};

// Checks `s` and clamps what may be clamped (grip, pedal; a non-unit quaternion is renormalised).
// On NonFinite or OutsideWorkspace `s` is left as it was and must not be used. Allocates nothing,
// never throws: called on the haptic and I/O threads.
SampleCheck bound_sample(DeviceSample& s) noexcept;

inline bool keeps(SampleCheck c) {
  return c == SampleCheck::Ok || c == SampleCheck::Clamped;
}

}  // namespace phaco
