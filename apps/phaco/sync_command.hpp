#pragma once
// `phaco sync --to URI [--db FILE] [--all] [--batch N] [--json]` (issue 21 item 2,
// docs/records.md): uploads a station's records to a training centre's PostgreSQL server. Exit
// codes as in commands.hpp: 0 success (every record is at the centre), 2 bad input or an
// unreachable centre (nothing acknowledged is lost; run it again), 3 when the centre refused some
// records.
#include <string>
#include <vector>

namespace phaco::cli {

int sync(const std::vector<std::string>& args);

}  // namespace phaco::cli
