#include "procedures/eye/resolution.hpp"

#include <string>

#include "engine/core/error.hpp"

namespace phaco::eye {

Resolution resolution_for_level(int level) {
  if (level < kMinLevel || level > kMaxLevel) {
    throw InputError("eye resolution level " + std::to_string(level) + " outside [" +
                     std::to_string(kMinLevel) + ", " + std::to_string(kMaxLevel) + "]");
  }
  return Resolution{level, 1000u << level, 6250u << level};
}

}  // namespace phaco::eye
