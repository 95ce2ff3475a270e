#include "engine/core/utc_time.hpp"

#include <cmath>
#include <cstdio>
#include <ctime>

namespace phaco {

std::string format_utc(double unix_seconds) {
  double whole = std::floor(unix_seconds);
  int ms = static_cast<int>(std::lround((unix_seconds - whole) * 1000.0));
  if (ms >= 1000) {
    ms -= 1000;
    whole += 1;
  }
  const std::time_t t = static_cast<std::time_t>(whole);
  std::tm tm{};
  gmtime_r(&t, &tm);
  char buf[96];  // sized for any int fields, which gmtime never gives, to keep -Wformat quiet
  std::snprintf(buf, sizeof buf, "%04d-%02d-%02dT%02d:%02d:%02d.%03dZ", tm.tm_year + 1900,
                tm.tm_mon + 1, tm.tm_mday, tm.tm_hour, tm.tm_min, tm.tm_sec, ms);
  return buf;
}

double unix_now_s() {
  timespec ts{};
  clock_gettime(CLOCK_REALTIME, &ts);
  return static_cast<double>(ts.tv_sec) + static_cast<double>(ts.tv_nsec) * 1e-9;
}

std::string utc_now() {
  return format_utc(unix_now_s());
}

std::optional<double> parse_utc(const std::string& text) {
  int y = 0, mo = 0, d = 0, h = 0, mi = 0, sec = 0, ms = 0, n = 0;
  if (text.size() != 24 ||
      std::sscanf(text.c_str(), "%4d-%2d-%2dT%2d:%2d:%2d.%3dZ%n", &y, &mo, &d, &h, &mi, &sec, &ms,
                  &n) != 7 ||
      n != 24)
    return std::nullopt;
  if (mo < 1 || mo > 12 || d < 1 || d > 31 || h > 23 || mi > 59 || sec > 60 || ms < 0)
    return std::nullopt;
  std::tm tm{};
  tm.tm_year = y - 1900, tm.tm_mon = mo - 1, tm.tm_mday = d;
  tm.tm_hour = h, tm.tm_min = mi, tm.tm_sec = sec;
  return static_cast<double>(timegm(&tm)) + ms * 1e-3;
}

}  // namespace phaco
