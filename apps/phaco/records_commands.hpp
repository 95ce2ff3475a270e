#pragma once
// `phaco history` and `phaco export` (issue 7 item 4, docs/records.md). Exit codes as in
// commands.hpp: 0 success, 2 bad input. What `phaco run --record` calls before and after a run
// is engine/records/record_run.hpp, shared with the trainer.
#include <string>
#include <vector>

#include "engine/records/record_run.hpp"

namespace phaco::cli {

// The CLI's names for them (tests/apps/test_records_cli.cpp calls them in phaco::cli).
using phaco::check_record_target;
using phaco::default_records_db;
using phaco::record_run;

// phaco history TRAINEE [--db FILE] [--json]: the trainee's records in date order (date, drill,
// score, the drill's key metrics) and, per drill, the trend (first -> last score, best).
int history(const std::vector<std::string>& args);

// phaco export ID [--db FILE] (--xml OUT | --json OUT | --scenario OUT)...: one record as XML
// (seed 000 §6.4), as one JSON object, or as the scenario file that `phaco run` replays.
int export_record(const std::vector<std::string>& args);

}  // namespace phaco::cli
