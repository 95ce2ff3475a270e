#include "engine/records/migrations.hpp"

namespace phaco::records {

namespace {

// Version 1 (issue 7): trainees and records. CHECKs keep a half-built row out even if a caller
// skips validation; the index serves the frequent query, a trainee's records in date order.
// PostgreSQL compares the UTC texts byte-wise (COLLATE "C"), as SQLite does, so text order stays
// date order whatever the server's locale.
constexpr const char* kV1Sqlite = R"sql(
CREATE TABLE trainees(
  id      INTEGER PRIMARY KEY,
  name    TEXT NOT NULL UNIQUE CHECK(length(name) > 0),
  created TEXT NOT NULL
);
CREATE TABLE records(
  id            INTEGER PRIMARY KEY,
  trainee_id    INTEGER NOT NULL REFERENCES trainees(id),
  drill         TEXT NOT NULL CHECK(length(drill) > 0),
  scenario_name TEXT NOT NULL,
  started_utc   TEXT NOT NULL,
  finished_utc  TEXT NOT NULL CHECK(finished_utc >= started_utc),
  settings      TEXT NOT NULL,
  metrics       TEXT NOT NULL,
  score         REAL CHECK(score IS NULL OR (score >= 0 AND score <= 100)),
  state_hash    TEXT NOT NULL,
  recording     TEXT NOT NULL,
  report        TEXT NOT NULL
);
CREATE INDEX records_by_trainee_date ON records(trainee_id, started_utc, id);
)sql";

constexpr const char* kV1Postgres = R"sql(
CREATE TABLE trainees(
  id      BIGSERIAL PRIMARY KEY,
  name    TEXT NOT NULL UNIQUE CHECK(length(name) > 0),
  created TEXT COLLATE "C" NOT NULL
);
CREATE TABLE records(
  id            BIGSERIAL PRIMARY KEY,
  trainee_id    BIGINT NOT NULL REFERENCES trainees(id),
  drill         TEXT NOT NULL CHECK(length(drill) > 0),
  scenario_name TEXT NOT NULL,
  started_utc   TEXT COLLATE "C" NOT NULL,
  finished_utc  TEXT COLLATE "C" NOT NULL CHECK(finished_utc >= started_utc),
  settings      TEXT NOT NULL,
  metrics       TEXT NOT NULL,
  score         DOUBLE PRECISION CHECK(score IS NULL OR (score >= 0 AND score <= 100)),
  state_hash    TEXT NOT NULL,
  recording     TEXT NOT NULL,
  report        TEXT NOT NULL
);
CREATE INDEX records_by_trainee_date ON records(trainee_id, started_utc, id);
)sql";

// Version 2 (issue 21): a record's identity is a UUID made where it was recorded, so a station
// can upload it to a centre any number of times and the centre keeps it once (the station's
// integer ids and clocks mean nothing elsewhere). Older records get a random version-4 UUID here.
// `synced` is the station's note of what each centre has already acknowledged.
constexpr const char* kV2Sqlite = R"sql(
ALTER TABLE records ADD COLUMN uuid TEXT;
UPDATE records SET uuid = lower(hex(randomblob(4)) || '-' || hex(randomblob(2)) || '-4' ||
  substr(hex(randomblob(2)), 2) || '-' || substr('89ab', 1 + (abs(random()) % 4), 1) ||
  substr(hex(randomblob(2)), 2) || '-' || hex(randomblob(6)));
CREATE UNIQUE INDEX records_by_uuid ON records(uuid);
CREATE TABLE synced(
  target     TEXT NOT NULL,
  uuid       TEXT NOT NULL,
  synced_utc TEXT NOT NULL,
  PRIMARY KEY(target, uuid)
) WITHOUT ROWID;
)sql";

constexpr const char* kV2Postgres = R"sql(
ALTER TABLE records ADD COLUMN uuid TEXT;
UPDATE records SET uuid = gen_random_uuid()::text;
ALTER TABLE records ALTER COLUMN uuid SET NOT NULL;
CREATE UNIQUE INDEX records_by_uuid ON records(uuid);
)sql";

constexpr Migration kMigrations[] = {
    {1, "trainees and records", kV1Sqlite, kV1Postgres},
    {2, "a UUID per record, and the station's sync notes", kV2Sqlite, kV2Postgres},
};

}  // namespace

std::span<const Migration> migrations() {
  return kMigrations;
}

int newest_schema_version() {
  return kMigrations[std::size(kMigrations) - 1].version;
}

}  // namespace phaco::records
