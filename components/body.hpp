#pragma once
// What a body entity is in the eye; its elements live in Particles / Triangles / Tets components.
#include <cstdint>
#include <string_view>

namespace phaco {

enum class BodyPart : uint8_t { Cornea, Capsule, Iris, Globe, LensSurface, Lens };

constexpr std::string_view to_string(BodyPart part) {
  switch (part) {
    case BodyPart::Cornea:
      return "cornea";
    case BodyPart::Capsule:
      return "capsule";
    case BodyPart::Iris:
      return "iris";
    case BodyPart::Globe:
      return "globe";
    case BodyPart::LensSurface:
      return "lens_surface";
    case BodyPart::Lens:
      return "lens";
  }
  return "unknown";
}

struct Body {
  BodyPart part = BodyPart::Capsule;
};

}  // namespace phaco
