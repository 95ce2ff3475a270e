#pragma once
// What RecordStore asks of a database (issue 21): the SQLite file of a station
// (sqlite_records.cpp) or a training centre's PostgreSQL server (postgres_records.cpp). Both hold
// the same schema (migrations.hpp) and answer the same queries; RecordStore validates a record
// before either sees it. Not thread-safe: one backend per thread or process.
#include <cstdint>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "engine/records/records.hpp"

namespace phaco::records {

class RecordBackend {
 public:
  virtual ~RecordBackend() = default;

  // Stores the records in one transaction, each keyed by its uuid: a uuid already stored is left
  // as it is. Returns, per record, its new id or 0 when it was already there. All or nothing.
  virtual std::vector<int64_t> add_records(std::span<const SessionRecord> records) = 0;

  virtual std::vector<SessionRecord> records_of(const std::string& trainee) const = 0;
  virtual std::optional<SessionRecord> record(int64_t id) const = 0;
  virtual std::optional<SessionRecord> record_by_uuid(const std::string& uuid) const = 0;
  virtual std::vector<SessionRecord> all_records() const = 0;
  virtual std::vector<std::string> trainees() const = 0;
  virtual int64_t count() const = 0;
  virtual std::string integrity_check() const = 0;
  virtual int schema_version() const = 0;
  virtual bool connected() const = 0;

  // The station's sync notes (SQLite only; the PostgreSQL backend refuses, naming the server).
  virtual std::vector<SessionRecord> not_synced_to(const std::string& target) const = 0;
  virtual void mark_synced(const std::string& target, std::span<const std::string> uuids) = 0;
};

std::unique_ptr<RecordBackend> open_sqlite(const std::string& file, OpenMode mode,
                                           int busy_timeout_ms);
std::unique_ptr<RecordBackend> open_postgres(const std::string& uri, int connect_timeout_s);

}  // namespace phaco::records
