#pragma once
// What one step of a procedure leaves to the next (issue 20 item 1, docs/procedures.md): the eye
// as the trainee left it. Plain data, made by procedures/procedure/carry at the end of a step and
// handed to the next step's build_scene (SceneOptions::carried); every field empty means the
// drill's own start state.
#include <array>
#include <cstdint>
#include <optional>
#include <vector>

#include "components/eye_ports.hpp"
#include "components/particles.hpp"
#include "engine/core/math.hpp"

namespace phaco {

// A membrane as it stands (cornea with its wound, capsule with its opening), compacted: only the
// triangles kept and the particles they use, in the positions they had.
struct CarriedSurface {
  std::vector<Vec3> vertices;
  std::vector<ParticleKind> kind;
  std::vector<float> inv_mass;
  std::vector<std::array<uint32_t, 3>> triangles;
};

struct CarriedState {
  std::optional<EyePort> main_port;       // the incision that was cut: replaces the "main" port
  std::optional<CarriedSurface> cornea;   // the cut cornea
  std::optional<CarriedSurface> capsule;  // the held capsule, the torn disc removed
  // The opening's equivalent radius (0: not closed, the bag is shut): the nucleus's containing
  // bounds free cells inside it (systems/lens_tools eye_bounds).
  std::optional<double> rhexis_radius_mm;
  std::optional<std::vector<uint32_t>> lens_removed;  // tet (= cell) ids sculpted away, ascending
};

}  // namespace phaco
