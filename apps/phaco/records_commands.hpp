#pragma once
// `phaco history` and `phaco export`, and the hook `phaco run --record` calls after a run
// (issue 7 item 4, docs/records.md). Exit codes as in commands.hpp: 0 success, 2 bad input.
#include <cstdint>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "engine/io/scenario.hpp"

namespace phaco::cli {

// $PHACO_RECORDS_DB, else $XDG_DATA_HOME/openphaco/records.sqlite, else
// ~/.local/share/openphaco/records.sqlite. Throws InputError when none can be formed.
std::filesystem::path default_records_db();

// phaco history TRAINEE [--db FILE] [--json]: the trainee's records in date order (date, drill,
// score, the drill's key metrics) and, per drill, the trend (first -> last score, best).
int history(const std::vector<std::string>& args);

// phaco export ID [--db FILE] (--xml OUT | --json OUT | --scenario OUT)...: one record as XML
// (seed 000 §6.4), as one JSON object, or as the scenario file that `phaco run` replays.
int export_record(const std::vector<std::string>& args);

// Checks, before a drill starts, that its record can be written: the trainee name is acceptable
// and the database opens (created if missing, with its directory). So a bad --trainee or --record
// fails in a second, not after the drill. Throws InputError.
void check_record_target(const std::filesystem::path& db, const std::string& trainee);

// Stores a finished run: `scenario` is what ran (its JSON becomes the recording), `report` the
// run report (to_json of RunReport, with "metrics" and "state_hash"). Creates the database and
// its directory when missing. Returns the new record's id; throws InputError naming the file.
int64_t record_run(const std::filesystem::path& db, const std::string& trainee,
                   const Scenario& scenario, const nlohmann::json& report);

}  // namespace phaco::cli
