#pragma once
// A haptic runtime stand-in for scene tests: no device (the tools follow their tracks), keeps the
// last published local model (procedures/scene/haptic_port.hpp).
#include <cstdint>

#include "procedures/scene/haptic_port.hpp"

namespace phaco::test {

class CapturePort final : public HapticPort {
 public:
  bool newest_pose(Hand, ToolPose&) override { return false; }
  HapticModel& model_slot() override { return slot; }
  void publish_model() override { ++published, last_sequence = slot.sequence; }
  HapticModel slot;
  uint64_t published = 0, last_sequence = 0;
};

}  // namespace phaco::test
