#include "apps/phaco/haptic_record.hpp"

#include <algorithm>
#include <charconv>
#include <cstdio>

#include "engine/core/error.hpp"
#include "engine/core/utc_time.hpp"
#include "engine/haptics/recording_device.hpp"
#include "engine/records/record_run.hpp"
#include "procedures/scene/run.hpp"

namespace phaco::cli {

std::unique_ptr<HapticRecording> HapticRecording::from_args(const Args& a, const Scenario& scenario,
                                                            Hand hand, const std::string& spec) {
  const auto trainee = a.option("--trainee");
  if (!a.option("--record") && !trainee) return nullptr;
  if (!trainee) throw InputError("run: --record needs --trainee NAME");
  const HandTrack* track = scenario.find_hand(hand);
  if (!track) {
    throw InputError(scenario.source + ": hands." + std::string(to_string(hand)) +
                     ": --haptics with --record records the device's hand as that hand's track; "
                     "the scenario must script it (its tool)");
  }
  auto r = std::make_unique<HapticRecording>();
  r->db_ =
      a.option("--record") ? std::filesystem::path(*a.option("--record")) : default_records_db();
  r->trainee_ = *trainee;
  r->spec_ = spec;
  r->hand_ = hand;
  r->tool_ = track->tool;
  check_record_target(r->db_, r->trainee_);
  // Capacity for the whole run at 1 kHz with a margin; an unparsable --duration is reported by
  // the run's own parsing, so the scenario's duration stands in here.
  double duration = scenario.duration_s;
  if (auto d = a.option("--duration")) {
    double v = 0;
    const auto [end, ec] = std::from_chars(d->data(), d->data() + d->size(), v);
    if (ec == std::errc{} && end == d->data() + d->size() && v > 0 && v <= 86400) duration = v;
  }
  r->recorder_ = std::make_unique<DeviceRecorder>(static_cast<std::size_t>(duration * 1500) + 4096);
  return r;
}

std::unique_ptr<Device> HapticRecording::wrap(std::unique_ptr<Device> device) {
  return recording_device(std::move(device), *recorder_);
}

int64_t HapticRecording::store(const Scenario& scenario, const SceneOptions& options,
                               const nlohmann::json& live, double duration_s) const {
  Scenario recorded = recorder_->scenario(scenario, hand_, tool_);
  // The live run's length, not the script's: the replay covers what was played.
  recorded.duration_s = std::max(duration_s, recorded.dt_s);
  recorded.description = "Recorded from device '" + spec_ + "' in the " +
                         std::string(to_string(hand_)) + " hand (phaco run --haptics); " +
                         recorded.description;
  const RunReport replay = run_scenario(recorded, options);
  nlohmann::json j = to_json(replay);
  j["date"] = utc_now();
  j["live"] = live;
  j["recorded_from"] = {{"device", spec_},
                        {"hand", std::string(to_string(hand_))},
                        {"samples", recorder_->size()},
                        {"dropped", recorder_->dropped()},
                        {"rejected", recorder_->rejected()}};
  const int64_t id = record_run(db_, trainee_, recorded, j);
  std::fprintf(stderr,
               "recorded as record %lld in %s (%zu device samples; metrics of the fixed-step "
               "replay of the recorded track, score %s)\n",
               static_cast<long long>(id), db_.c_str(), recorder_->size(),
               replay.metrics.contains("score") ? replay.metrics["score"].dump().c_str() : "-");
  return id;
}

}  // namespace phaco::cli
