#pragma once
// Calendar time, UTC, in the one format the records and run reports store:
// "2026-11-21T19:30:00.123Z" (ISO 8601 with milliseconds; sorts as text in time order).
#include <optional>
#include <string>

namespace phaco {

// `unix_seconds` since the Unix epoch, rounded to the millisecond.
std::string format_utc(double unix_seconds);
// Now.
std::string utc_now();
// Seconds since the Unix epoch now (the realtime clock).
double unix_now_s();
// The inverse of format_utc: seconds since the Unix epoch, or nullopt when `text` is not in the
// format (exactly "YYYY-MM-DDTHH:MM:SS.mmmZ", fields in range).
std::optional<double> parse_utc(const std::string& text);

}  // namespace phaco
