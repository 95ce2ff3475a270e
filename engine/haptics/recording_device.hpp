#pragma once
// A device whose samples are also recorded (issue 7 item 4, docs/records.md;
// docs/trainer_threads.md): `phaco run --haptics --record` and the trainer session wrap each device
// with it, so every new sample the haptic thread reads also goes to a DeviceRecorder
// (engine/haptics/replay_device.hpp: capacity reserved up front, no allocation and no lock on the
// haptic thread). The recording then becomes the scenario that replays the run.
//
// With a RecordingClock (the trainer's pause): while it says paused nothing is recorded, and the
// paused time so far is taken out of the samples' times, so the recording lines up with the
// simulated time. Without one every sample is recorded as read.
#include <atomic>
#include <cstdint>
#include <memory>

#include "engine/haptics/device.hpp"
#include "engine/haptics/replay_device.hpp"

namespace phaco {

// Shared between the UI thread (pause, resume) and the haptic thread (the wrapped devices).
struct RecordingClock {
  std::atomic<bool> paused{false};
  std::atomic<int64_t> paused_ns{0};  // total paused time so far, ns
};

// `inner` with every new sample it reads kept in `recorder` (not while clock->paused). The
// recorder and the clock must outlive the returned device; `clock` may be null (never paused).
std::unique_ptr<Device> recording_device(std::unique_ptr<Device> inner, DeviceRecorder& recorder,
                                         const RecordingClock* clock = nullptr);

}  // namespace phaco
