#pragma once
// The cache-line size used to keep data written by different threads apart (false sharing).
// A fixed 64 rather than std::hardware_destructive_interference_size, whose value g++ warns may
// change between compiler versions and flags (it would change struct layouts across libraries).
#include <cstddef>

namespace phaco {

inline constexpr std::size_t kCacheLine = 64;  // bytes, x86-64 and most ARM64 cores

}  // namespace phaco
