#pragma once
// The calendar time of records and reports, in UTC.
#include <ctime>
#include <string>

namespace phaco {

// `t` as "2026-11-21T19:30:00Z" (ISO 8601, what the records and run reports store).
std::string utc_iso8601(std::time_t t);
// Now, as above.
inline std::string utc_now() {
  return utc_iso8601(std::time(nullptr));
}

}  // namespace phaco
