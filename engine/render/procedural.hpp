#pragma once
// CPU-side procedural content of the renderer (private to engine/render): the instrument meshes
// and the iris and sclera textures. Made once when the Renderer is built; no GL here, so the shapes
// can be checked without a context.
//
// Instrument frame: the tip at the origin, the shaft along local +z (toward the handpiece; the
// snapshot's quat turns it into the eye frame). Sizes from DESIGN.md §6 (phaco tip 0.9 mm outer
// diameter, keratome blade 2.4 mm wide, cystotome bent tip 0.3 mm).
#include <array>
#include <cstdint>
#include <vector>

#include "engine/io/scenario.hpp"

namespace phaco::render {

struct ToolMesh {
  std::vector<float> xyz;      // 3 per vertex, mm, instrument frame
  std::vector<float> normal;   // 3 per vertex, unit
  std::vector<uint32_t> tris;  // 3 per triangle
};

struct ToolMeshes {
  ToolMesh body;  // everything that moves with the handpiece
  ToolMesh jaw;   // forceps only: one jaw, drawn twice, turned about kForcepsPivotZ
};

constexpr float kForcepsJawLength = 8.0f;         // mm, tip to the pivot where the jaws join
constexpr float kForcepsOpenHalfAngleDeg = 9.0f;  // each jaw's angle at grip 0
constexpr float kPhacoTipLength = 1.5f;           // mm of bare titanium tip before the sleeve
constexpr float kShaftLength = 40.0f;             // mm drawn; enough to leave a 16 mm field

ToolMeshes make_tool_mesh(ToolKind kind);

struct TextureImage {
  int width = 0, height = 0;
  std::vector<uint8_t> rgb;  // rows bottom to top (GL order)
};

// Polar image: u = angle about the optical axis / 2π, v = 0 at the pupil margin .. 1 at the root.
TextureImage make_iris_texture(bool blue);
// The polar iris resampled onto a square covering the disc of the iris root's radius (what the
// shader samples with x, y: no atan and no seam per pixel). pupil_ratio = pupil / root radius.
TextureImage bake_iris_disc(const TextureImage& polar, double pupil_ratio, int size = 512);
// The globe's front hemisphere seen from +z: square over x, y in [−R, R] (R the globe radius),
// white with red vessels running in from the periphery toward the limbus.
TextureImage make_sclera_texture();

}  // namespace phaco::render
