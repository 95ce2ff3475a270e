#include "engine/records/records.hpp"

#include <cmath>
#include <cstdio>
#include <random>

#include "engine/core/error.hpp"
#include "engine/records/record_backend.hpp"
#include "engine/records/record_location.hpp"

namespace phaco {

namespace {

// What both backends need of a record before it is stored; the schema's CHECKs are the last
// line, this is the one that names the problem.
void check_record(const SessionRecord& r, const std::string& db) {
  if (r.trainee.empty()) throw InputError(db + ": a record needs a trainee name");
  // PostgreSQL's text cannot hold a NUL character; SQLite's could, but the record must be able to
  // go to a centre.
  for (const std::string* s : {&r.trainee, &r.drill, &r.scenario_name, &r.state_hash})
    if (s->find('\0') != std::string::npos)
      throw InputError(db + ": a record's text contains a NUL character");
  if (r.score && !std::isfinite(*r.score)) {
    throw InputError(db + ": record score is not a finite number");
  }
}

}  // namespace

std::string new_record_uuid() {
  // Fresh bits from the kernel every time (not a seeded generator: a forked process would repeat
  // its parent's sequence, and two stations' records must never share an identity).
  std::random_device device;
  const auto bits64 = [&] { return static_cast<uint64_t>(device()) << 32 | device(); };
  uint64_t hi = bits64(), lo = bits64();
  hi = (hi & ~0xf000ull) | 0x4000ull;        // version 4
  lo = (lo & ~(3ull << 62)) | (2ull << 62);  // variant 10
  char buf[37];
  std::snprintf(buf, sizeof buf, "%08llx-%04llx-%04llx-%04llx-%012llx",
                static_cast<unsigned long long>(hi >> 32),
                static_cast<unsigned long long>((hi >> 16) & 0xffff),
                static_cast<unsigned long long>(hi & 0xffff),
                static_cast<unsigned long long>(lo >> 48),
                static_cast<unsigned long long>(lo & 0xffffffffffffull));
  return buf;
}

RecordStore::RecordStore(const std::filesystem::path& location, OpenMode mode, int busy_timeout_ms)
    : shown_(shown_location(location.string())), server_(is_postgres_uri(location.string())) {
  if (location.empty()) throw InputError("no records database given (an empty --db or PHACO_DB)");
  backend_ = server_ ? records::open_postgres(location.string(), kConnectTimeoutS)
                     : records::open_sqlite(location.string(), mode, busy_timeout_ms);
}

RecordStore::~RecordStore() = default;

int64_t RecordStore::add_record(const SessionRecord& record) {
  check_record(record, shown_);
  SessionRecord r = record;
  if (r.uuid.empty()) r.uuid = new_record_uuid();
  const int64_t id = backend_->add_records({&r, 1}).front();
  if (id == 0) throw InputError(shown_ + ": record " + r.uuid + " is already stored");
  return id;
}

size_t RecordStore::add_missing(std::span<const SessionRecord> records) {
  for (const SessionRecord& r : records) {
    check_record(r, shown_);
    if (r.uuid.empty()) throw InputError(shown_ + ": a record to upload has no uuid");
  }
  size_t added = 0;
  for (const int64_t id : backend_->add_records(records)) added += id != 0;
  return added;
}

std::vector<SessionRecord> RecordStore::records_of(const std::string& trainee) const {
  return backend_->records_of(trainee);
}
std::optional<SessionRecord> RecordStore::record(int64_t id) const {
  return backend_->record(id);
}
std::optional<SessionRecord> RecordStore::record_by_uuid(const std::string& uuid) const {
  return backend_->record_by_uuid(uuid);
}
std::vector<SessionRecord> RecordStore::all_records() const {
  return backend_->all_records();
}
std::vector<std::string> RecordStore::trainees() const {
  return backend_->trainees();
}
int64_t RecordStore::count() const {
  return backend_->count();
}
std::string RecordStore::integrity_check() const {
  return backend_->integrity_check();
}
bool RecordStore::connected() const {
  return backend_->connected();
}
int RecordStore::schema_version() const {
  return backend_->schema_version();
}
std::vector<SessionRecord> RecordStore::not_synced_to(const std::string& target) const {
  return backend_->not_synced_to(target);
}
void RecordStore::mark_synced(const std::string& target, std::span<const std::string> uuids) {
  backend_->mark_synced(target, uuids);
}

}  // namespace phaco
