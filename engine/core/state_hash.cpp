#include "engine/core/state_hash.hpp"

#include <cstdio>

namespace phaco {

std::string StateHash::hex() const {
  char buf[17];
  std::snprintf(buf, sizeof buf, "%016llx", static_cast<unsigned long long>(value()));
  return buf;
}

}  // namespace phaco
