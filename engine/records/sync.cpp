#include "engine/records/sync.hpp"

#include <algorithm>
#include <span>

#include "engine/core/error.hpp"

namespace phaco {

namespace {

std::vector<std::string> uuids_of(std::span<const SessionRecord> records) {
  std::vector<std::string> out;
  out.reserve(records.size());
  for (const SessionRecord& r : records) out.push_back(r.uuid);
  return out;
}

}  // namespace

SyncResult sync_records(RecordStore& station, RecordStore& centre, const SyncOptions& options) {
  if (station.is_server()) throw InputError(station.location() + ": sync from a station's file");
  if (!centre.is_server()) throw InputError(centre.location() + ": sync to a PostgreSQL URI");
  // The key under which the station notes acknowledgements: the centre's URI with its password
  // masked, so changing the password does not send everything again.
  const std::string& target = centre.location();
  const std::vector<SessionRecord> pending =
      options.resend_all ? station.all_records() : station.not_synced_to(target);
  SyncResult out;
  out.pending = pending.size();
  const size_t batch = std::max<size_t>(1, options.batch);
  for (size_t first = 0; first < pending.size(); first += batch) {
    const std::span<const SessionRecord> part(pending.data() + first,
                                              std::min(batch, pending.size() - first));
    std::vector<std::string> acknowledged;
    try {
      const size_t added = centre.add_missing(part);
      out.uploaded += added;
      out.already_there += part.size() - added;
      acknowledged = uuids_of(part);
    } catch (const InputError&) {
      // A lost connection fails every record alike: stop, and let the next sync go on.
      if (!centre.connected()) throw;
      // Otherwise one record's content (say, text the server's encoding refuses) must not hold
      // back the rest: send them one by one.
      for (const SessionRecord& r : part) {
        try {
          const size_t added = centre.add_missing({&r, 1});
          out.uploaded += added;
          out.already_there += 1 - added;
          acknowledged.push_back(r.uuid);
        } catch (const InputError& e) {
          if (!centre.connected()) {
            station.mark_synced(target, acknowledged);
            throw;
          }
          out.refused.push_back(r.uuid + ": " + e.what());
        }
      }
    }
    station.mark_synced(target, acknowledged);
    if (options.progress) options.progress(first + part.size());
  }
  return out;
}

}  // namespace phaco
