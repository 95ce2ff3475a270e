#pragma once
// Recording what the devices did, and storing a finished drill in the records database (issue 7
// item 4, docs/records.md), for the trainer session; the approach of apps/phaco/haptic_record
// (`phaco run --haptics --record`) as library code, for any number of device-driven hands.
//
// Each device is wrapped so every sample the haptic thread reads also goes to a DeviceRecorder
// (engine/haptics/replay_device.hpp: capacity reserved up front, no allocation on the haptic
// thread). While the session is paused nothing is recorded and the paused time is taken out of
// the samples' times, so the recording lines up with the simulated time. After the live run the
// recorded tracks replace the scenario's tracks of those hands; that scenario is run once more at
// the fixed step, headless, and stored with the replay's metrics and state hash (so replaying the
// record reproduces them exactly) and the live run's figures under "live".
#include <atomic>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>

#include "engine/haptics/device.hpp"
#include "engine/haptics/replay_device.hpp"
#include "engine/io/scenario.hpp"
#include "procedures/scene/scene.hpp"

namespace phaco {

// Shared between the UI thread (pause) and the haptic thread (the wrapped devices).
struct RecordingClock {
  std::atomic<bool> paused{false};
  std::atomic<int64_t> paused_ns{0};  // total paused time so far, ns
};

// `inner` with every new sample it reads kept in `recorder` (not while clock.paused).
std::unique_ptr<Device> recording_device(std::unique_ptr<Device> inner, DeviceRecorder& recorder,
                                         const RecordingClock& clock);

// The records database's default file: $PHACO_RECORDS_DB, else $XDG_DATA_HOME/openphaco/
// records.sqlite, else ~/.local/share/openphaco/records.sqlite (as `phaco run --record`).
std::filesystem::path trainer_records_db();

// Before a drill: the trainee's name is acceptable and the database opens (created if missing,
// with its directory), so a bad name or file fails in a second, not after the drill. InputError.
void check_session_record_target(const std::filesystem::path& db, const std::string& trainee);

// Stores a finished run (the scenario that replays it and its report JSON, with "metrics" and
// "state_hash") for `trainee`; creates the file and its directory. Returns the record id.
// Throws InputError naming the file.
int64_t store_session_record(const std::filesystem::path& db, const std::string& trainee,
                             const Scenario& scenario, const nlohmann::json& report);

}  // namespace phaco
