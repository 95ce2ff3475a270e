#pragma once
// What a scene needs of a haptic runtime (DESIGN.md §5): at the start of a frame, the newest
// device pose per hand (drained from the haptic thread's ring; a hand without a device keeps its
// scripted track), and at the end of it a slot to fill with the local haptic model and a call to
// publish it (the triple buffer's write side). Implemented by procedures/haptics' HapticSession;
// called on the simulation thread only, once per frame.
#include "components/haptic_model.hpp"
#include "engine/io/scenario.hpp"
#include "engine/io/track.hpp"

namespace phaco {

class HapticPort {
 public:
  virtual ~HapticPort() = default;
  // True when a device drives `hand` (its track is then not played).
  virtual bool drives(Hand) const { return false; }
  // True when `hand`'s device has given a pose; `pose` is then its newest sample (held when the
  // device is silent, so the tool freezes). False before the first sample and without a device.
  virtual bool newest_pose(Hand hand, ToolPose& pose) = 0;
  virtual HapticModel&
  model_slot() = 0;  // the slot to fill this frame (never read by the haptic thread)
  virtual void publish_model() = 0;
};

}  // namespace phaco
