#pragma once
// Offline-first stations (issue 21 item 2): a station always records to its own SQLite file; a
// sync uploads to the centre what the centre has not acknowledged yet.
//
// Why it never loses or duplicates a record, whatever stops it:
//   - the centre keys records by uuid and keeps a uuid once (ON CONFLICT DO NOTHING), so sending a
//     record twice (a second sync, two syncs at once, a retry after a cut) stores it once;
//   - the station notes a batch as acknowledged only after the centre committed it. A sync killed
//     between the two sends that batch again next time, and the centre keeps it once.
//   - a batch is one transaction on the centre: it lands whole or not at all.
// A station's clock may be wrong: records are sent in recorded-time order, but identity is the
// uuid alone.
#include <cstddef>
#include <functional>
#include <string>
#include <vector>

#include "engine/records/records.hpp"

namespace phaco {

struct SyncOptions {
  size_t batch = 50;  // records per transaction on the centre
  // Send every record again, not only those the station has no acknowledgement for (after the
  // centre lost data, say); the centre still keeps each once.
  bool resend_all = false;
  // Called after each batch the centre committed, with the records sent so far.
  std::function<void(size_t sent)> progress;
};

struct SyncResult {
  size_t pending = 0;                // records the station had to send
  size_t uploaded = 0;               // of which the centre stored now
  size_t already_there = 0;          // of which the centre had already
  std::vector<std::string> refused;  // "uuid: why", records the centre refused (kept, sent again)
};

// Uploads `station`'s records to `centre`. Throws InputError (naming the centre, password masked)
// when the centre cannot be reached or the connection is lost; what was acknowledged before that
// stays acknowledged, the rest is sent by the next sync. A record the centre refuses for its
// content is reported in `refused` and does not stop the others.
SyncResult sync_records(RecordStore& station, RecordStore& centre, const SyncOptions& options = {});

}  // namespace phaco
