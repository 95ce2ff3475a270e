#pragma once
// Storing a finished run in the records database (issue 7 item 4, docs/records.md), for
// `phaco run --record` (apps/phaco) and the trainer session (procedures/trainer): where the
// database is by default, the checks made before a drill, and the record made after it.
//
// A record keeps the scenario that replays the run (its JSON is the recording) next to the run
// report's metrics and state hash. Not for hot paths: file I/O; errors are InputError with a
// message naming the file or the problem.
#include <cstdint>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>

#include "engine/core/utc_time.hpp"  // unix_now_s(): the clock record_run reads
#include "engine/io/scenario.hpp"

namespace phaco {

// $PHACO_DB (a file or a postgresql:// URI), else $PHACO_RECORDS_DB (the older name), else
// $XDG_DATA_HOME/openphaco/records.sqlite, else ~/.local/share/openphaco/records.sqlite. Throws
// InputError when none can be formed.
std::filesystem::path default_records_db();

// Checks, before a drill starts, that its record can be written: the trainee name is acceptable
// and the database opens (created if missing, with its directory). So a bad name or file fails
// in a second, not after the drill. Throws InputError.
void check_record_target(const std::filesystem::path& db, const std::string& trainee);

// Stores a finished run: `scenario` is what replays it (its JSON becomes the recording),
// `report` the run report (to_json of RunReport, with "metrics" and "state_hash"). The run
// started `run_s` wall seconds before now; without it, the report's wall_time_s + mesh_load_s
// (a headless run's own clock). `finished_unix_s`: when the run ended (s since the Unix epoch),
// for a record stored later than that (the trainer's "save again"); default now. Creates the
// database and its directory when missing. Returns the new record's id; throws InputError naming
// the file.
int64_t record_run(const std::filesystem::path& db, const std::string& trainee,
                   const Scenario& scenario, const nlohmann::json& report,
                   std::optional<double> run_s = std::nullopt,
                   std::optional<double> finished_unix_s = std::nullopt);

}  // namespace phaco
