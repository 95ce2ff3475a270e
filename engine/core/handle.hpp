#pragma once
// Generational handle: an index into a flat table plus the generation the slot had when the
// handle was made. Reusing a slot bumps its generation, so a handle kept across a removal is
// detected as stale instead of silently pointing at a new element.
#include <cstdint>
#include <functional>

namespace phaco {

inline constexpr uint32_t kInvalidIndex = 0xFFFFFFFFu;

struct Handle {
  uint32_t index = kInvalidIndex;
  uint32_t generation = 0;

  bool is_null() const { return index == kInvalidIndex; }
  friend bool operator==(const Handle&, const Handle&) = default;
};

}  // namespace phaco

template <>
struct std::hash<phaco::Handle> {
  size_t operator()(const phaco::Handle& h) const noexcept {
    return std::hash<uint64_t>{}((uint64_t{h.generation} << 32) | h.index);
  }
};
