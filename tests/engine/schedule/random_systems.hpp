#pragma once
// Deterministic pseudo-random system sets for property tests of the graph and the executor.
#include <cstdint>
#include <string>
#include <vector>

#include "engine/schedule/system.hpp"

namespace phaco::test {

// "s12", "c3": appended rather than "s" + std::to_string(n), which trips a GCC 12 false warning.
inline std::string label(char prefix, uint32_t n) {
  std::string s(1, prefix);
  s += std::to_string(n);
  return s;
}

// Systems with random phases and random reads/writes over `components` names "c0".."cK"; every
// tenth system is a barrier when `barriers` is set. `run` is left for the caller.
inline std::vector<SystemDesc> random_systems(uint32_t count, uint32_t components, uint64_t seed,
                                              bool barriers = true) {
  uint64_t state = seed * 0x9E3779B97F4A7C15ull + 1;
  auto next = [&state](uint32_t bound) {
    state = state * 6364136223846793005ull + 1442695040888963407ull;
    return static_cast<uint32_t>((state >> 33) % bound);
  };
  std::vector<SystemDesc> systems;
  for (uint32_t i = 0; i < count; ++i) {
    SystemDesc s;
    s.name = label('s', i);
    s.phase = static_cast<Phase>(next(kPhaseCount));
    for (uint32_t c = 0; c < components; ++c) {
      const uint32_t roll = next(10);
      if (roll == 0)
        s.writes.push_back(label('c', c));
      else if (roll <= 2)
        s.reads.push_back(label('c', c));
    }
    s.barrier = barriers && i % 10 == 9;
    systems.push_back(std::move(s));
  }
  return systems;
}

}  // namespace phaco::test
