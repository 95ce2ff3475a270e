#pragma once
// The records schema as a list of versioned migrations, one per version, each written for both
// backends (issue 21). A database at version v is brought to the newest by applying migrations
// v+1 … in order, each in its own transaction with the version bump, so an upgrade interrupted at
// any point leaves a database at some whole version. A database newer than the newest here is
// refused, never read (docs/records.md, "Versions").
//
// Where a version lives: SQLite's PRAGMA user_version; PostgreSQL's one-row table phaco_schema.
#include <cstdint>
#include <span>

namespace phaco::records {

struct Migration {
  int version;           // the version a database has after this migration
  const char* what;      // one line for docs and error messages
  const char* sqlite;    // statements for SQLite
  const char* postgres;  // the same change for PostgreSQL
};

std::span<const Migration> migrations();

// The advisory lock (pg_advisory_xact_lock) a PostgreSQL database's schema is created and
// upgraded under, so that stations meeting it at once apply each migration once.
inline constexpr int64_t kPostgresSchemaLock = 0x7068'6163'6f00;  // "phaco"

// The newest version (the last migration's).
int newest_schema_version();

}  // namespace phaco::records
