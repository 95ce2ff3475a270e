#pragma once
// The lens's thickness map on the GPU, for the two lens looks (private to engine/render; issue 19
// item 4). Sculpting a trainee can see, as a surgeon sees it through the microscope:
//   - the red reflex through the lens brightens where the nucleus under it is thin. Surgeons judge
//     a trench's depth by it: the floor's reflex turns bright red-orange as the trench nears the
//     posterior plate, the usual stop at about 80–90 % of the nucleus's depth (divide and conquer:
//     Gimbel 1991; Seibel, "Phacodynamics"). The shader dims the reflex by exp(−μ t), t the
//     remaining thickness from the map, μ the body's reflex_attenuation_per_mm;
//   - the trench's walls are shaded: the normal of the top surface the microscope sees, from the
//     slope of the map's top heights (over two cells either side), so a groove reads as a
//     groove at the trench's scale and not as the tets' facets.
// The texture (RGBA32F, size²): r = thickness mm, g, b = the top surface's unit normal x, y (its z
// follows), a = 1 where the line meets the lens, else 0. Re-sent only when a lens body's vertices
// or triangles changed since the last frame.
#include <epoxy/gl.h>

#include <array>
#include <vector>

#include "engine/render/lens_thickness.hpp"
#include "engine/render/renderer.hpp"

namespace phaco::render {

class LensReflexMap {
 public:
  static constexpr int kSize = 128;  // cells per side: 0.08 mm on the standard lens (9.4 mm)

  LensReflexMap();  // needs the renderer's GL context
  ~LensReflexMap();
  LensReflexMap(const LensReflexMap&) = delete;
  LensReflexMap& operator=(const LensReflexMap&) = delete;

  // Rebuilds the map from the snapshot's lens bodies (looks LensSurface and LensInterior) when they
  // changed; counts one upload in stats when it re-sends them (the texture and the fundus disc).
  void update(const RenderSnapshot& s, FrameStats& stats);
  // Binds the texture on `unit` and points `program`'s u_lens_map uniforms at it (leaves
  // `program` in use).
  void bind(GLuint program, int unit) const;
  // The fundus's glow behind the lens: a disc just below its posterior pole, as wide as the lens,
  // drawn with the lens surface's `program` as a clear lens (the reflex undimmed), so wherever no
  // lens is left on the line of sight (a crack between fragments, a lens removed) the pupil shows
  // the bright reflex of the fundus seen through the posterior capsule, as in surgery. Nothing
  // without a lens body.
  void draw_fundus(GLuint program, FrameStats& stats) const;

  const ThicknessMap& map() const { return map_; }

 private:
  bool changed(const RenderSnapshot& s);

  static constexpr int kFundusSegments = 48;

  // Two of each, written in turn (lens_reflex.cpp says why).
  struct Slot {
    GLuint texture = 0;
    int size = 1;  // texels per side
    GLuint fundus_vao = 0, fundus_positions = 0;
  };
  Slot slots_[2];
  int current_ = 0;  // the slot drawn with
  GLuint fundus_normals_ = 0;
  bool has_lens_ = false;
  ThicknessMap map_;
  std::vector<std::array<float, 4>> texels_;
  std::vector<const BodyView*> lens_;
  // What the map was built from: per lens body its version and vertices.
  std::vector<uint64_t> built_versions_;
  std::vector<std::vector<float>> built_xyz_;
};

}  // namespace phaco::render
