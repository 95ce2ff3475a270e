#include "engine/records/record_location.hpp"

namespace phaco {

bool is_postgres_uri(std::string_view location) {
  return location.starts_with("postgresql://") || location.starts_with("postgres://");
}

std::string shown_location(std::string_view location) {
  if (!is_postgres_uri(location)) return std::string(location);
  std::string out(location);
  // user-info: between "://" and the last '@' before the query. Not before the first '/': a
  // password with an unencoded '/' is not a valid URI, but must not show either.
  const size_t start = out.find("://") + 3;
  const size_t query_start = out.find('?', start);
  const size_t at = out.rfind('@', query_start == std::string::npos ? out.size() : query_start);
  if (at != std::string::npos && at >= start) {
    const size_t colon = out.find(':', start);
    if (colon != std::string::npos && colon < at) out.replace(colon + 1, at - colon - 1, "***");
  }
  // query parameters: "password=…" up to the next '&'.
  const size_t query = out.find('?', start);
  for (size_t p = query; p != std::string::npos && p < out.size();) {
    const size_t key = p + 1;
    if (out.compare(key, 9, "password=") == 0) {
      const size_t end = out.find('&', key);
      out.replace(key + 9, (end == std::string::npos ? out.size() : end) - key - 9, "***");
    }
    p = out.find('&', key);
  }
  return out;
}

}  // namespace phaco
