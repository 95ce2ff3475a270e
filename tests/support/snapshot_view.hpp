#pragma once
// A render snapshot's body view by name, for the trainer's tests.
#include <string>

#include "engine/render/snapshot.hpp"

namespace phaco::test {

inline const render::BodyView* find_view(const render::RenderSnapshot& s, const std::string& name) {
  for (const auto& b : s.bodies)
    if (b.name == name) return &b;
  return nullptr;
}

}  // namespace phaco::test
