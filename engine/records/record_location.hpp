#pragma once
// Where records live (issue 21): a station's SQLite file (a path) or a training centre's
// PostgreSQL server (a libpq URI, "postgresql://user:password@host:port/dbname?…"). The same
// `--db` option and PHACO_DB variable take either.
//
// A URI may carry a password. It is never printed: every message and every key derived from a
// location goes through shown_location, which masks it.
#include <string>
#include <string_view>

namespace phaco {

// True for "postgresql://…" and "postgres://…" (the two prefixes libpq accepts).
bool is_postgres_uri(std::string_view location);

// The location as it may be printed: a URI's password (in its user-info part or as a
// "password=" query parameter) replaced by "***"; a path unchanged.
std::string shown_location(std::string_view location);

}  // namespace phaco
