#pragma once
// The surgical microscope's view of a RenderSnapshot in OpenGL 3.3 core (issue 8 item 1). Needs a
// current GL 3.3 core context (the trainer's GLFW window, or a hidden one in tests); GL functions
// come from libepoxy. Draws into the bound framebuffer's viewport; owns its shaders, buffers and
// textures (created in the constructor, released in the destructor, same context).
//
// The view: the microscope looks down the optical axis (−z) from above the cornea; zoom sets the
// field of view (the visible diameter at the focal plane), focus the depth of the focal plane
// (depth of field: detail away from it is softened). Optional side-by-side stereo (seed 003's
// HMD): two views with the microscope's stereo base.
#include <array>
#include <cstdint>
#include <filesystem>
#include <span>
#include <stdexcept>
#include <string>
#include <vector>

#include "engine/render/snapshot.hpp"

namespace phaco::render {

struct RenderError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

struct Microscope {
  double field_mm = 16.0;   // visible diameter at the focal plane (zoom)
  double focus_z_mm = 1.8;  // focal plane height on the optical axis (the capsule's apex)
  double working_distance_mm = 200.0;  // objective to focal plane
  double stereo_base_mm = 22.0;        // between the two eyepieces' axes at the objective
  Vec3 centre_mm = Vec3::Zero();       // what the view centres on (x, y; z ignored)
  double depth_of_field_mm = 2.0;      // sharp within ±half of it about focus_z, softer beyond
};

enum class StereoMode : uint8_t { Mono, SideBySide };

struct RenderOptions {
  StereoMode stereo = StereoMode::Mono;
  bool guidance = true;    // overlays of the drill's cues
  bool shadows = true;     // tool shadows on the tissue (depth cue)
  bool blue_iris = false;  // iris texture: brown (default) or blue
};

// A rectangle of the window in pixels (row 0 at the top) that something opaque drawn after the
// view will cover, such as the trainer's panels.
struct PixelRect {
  float x0 = 0, y0 = 0, x1 = 0, y1 = 0;
};

struct FrameStats {
  uint32_t triangles = 0;  // drawn this frame
  uint32_t draw_calls = 0;
  uint32_t uploads = 0;  // buffers re-uploaded (vertex data every frame; indices on topology)
};

class Renderer {
 public:
  // Compiles the shaders, makes the textures (iris, sclera: procedural) and tool meshes.
  // Throws RenderError with the GL version / shader log when the context cannot do it.
  explicit Renderer(const RenderOptions& options = {});
  ~Renderer();
  Renderer(const Renderer&) = delete;
  Renderer& operator=(const Renderer&) = delete;

  // Draws the snapshot into the current framebuffer's (0, 0, width, height). `covered`: parts of
  // it that will be painted over opaquely; the view is not shaded there (a depth pre-pass at the
  // near plane), which on a software renderer saves what shading them would cost.
  FrameStats draw(const RenderSnapshot& snapshot, const Microscope& microscope, int width,
                  int height, std::span<const PixelRect> covered = {});

  // Flat opaque rectangles of colour `rgba` (no blending, no depth test) over the current
  // framebuffer's (0, 0, width, height): the trainer's panel backgrounds, which on a software
  // renderer cost a fraction of ImGui's blended, textured ones.
  FrameStats fill(std::span<const PixelRect> rects, const std::array<float, 4>& rgba, int width,
                  int height);

  RenderOptions& options() { return options_; }

 private:
  struct Impl;
  Impl* impl_;
  RenderOptions options_;
};

// Where an eye-frame point (mm, after any globe rotation) lands in a mono view of width × height:
// pixel column and row (row 0 at the top), as draw() would put it. For tests and picking.
std::array<double, 2> project_to_pixel(const Microscope& microscope, const Vec3& point_mm,
                                       int width, int height);

// The bound framebuffer's pixels (RGB, rows top to bottom) — tests check these.
std::vector<uint8_t> read_pixels(int width, int height);
// Writes the bound framebuffer as a PNG (OpenCV). Throws RenderError naming the file on failure.
void save_screenshot(const std::filesystem::path& file, int width, int height);

}  // namespace phaco::render
