#pragma once
// `phaco run FILE --haptics SPEC --record DB --trainee NAME` (issue 7 item 4, docs/records.md):
// a real-time run stored as a record whose recording is the scenario with the device's hand
// replaced by the track the device actually produced.
//
// The device is wrapped so every sample the haptic thread reads also goes to a DeviceRecorder
// (engine/haptics/recording_device.hpp; no allocation on the haptic thread, capacity reserved up
// front). After the live run the recorded track becomes the scenario (duration: the live run's),
// that scenario is run once more at the fixed step, headless, and the record stores it with that
// replay's metrics and state hash, plus the live run's real-time report under "live". So
// `phaco export ID --scenario` followed by `phaco run` reproduces the stored metrics and hash
// exactly; the live run's own steps were paced by the wall clock and may differ (docs/records.md).
#include <cstdint>
#include <filesystem>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>

#include "apps/phaco/args.hpp"
#include "engine/haptics/device.hpp"
#include "engine/haptics/replay_device.hpp"
#include "engine/io/scenario.hpp"
#include "procedures/scene/scene.hpp"

namespace phaco::cli {

class HapticRecording {
 public:
  // nullptr when neither --record nor --trainee is given. Otherwise checks, before the run, that
  // the record can be written and that the scenario scripts `hand` (its tool is the recorded
  // track's tool). Throws InputError.
  static std::unique_ptr<HapticRecording> from_args(const Args& a, const Scenario& scenario,
                                                    Hand hand, const std::string& device_spec);

  // The device as the session should see it: the same device, its samples recorded.
  std::unique_ptr<Device> wrap(std::unique_ptr<Device> device);

  // After the live run (the session stopped): stores the record; `live` is the real-time
  // report's JSON, `duration_s` the live run's length. Returns the record id.
  int64_t store(const Scenario& scenario, const SceneOptions& options, const nlohmann::json& live,
                double duration_s) const;

 private:
  std::filesystem::path db_;
  std::string trainee_, spec_;
  Hand hand_ = Hand::Right;
  ToolKind tool_ = ToolKind::Forceps;
  std::unique_ptr<DeviceRecorder> recorder_;
};

}  // namespace phaco::cli
