#pragma once
// An off-screen framebuffer (RGBA8 colour, 24-bit depth, 8-bit stencil) to draw into where a
// window's own framebuffer is not dependable: hidden windows under Xvfb (tests), screenshots at a
// size other than the window's. Needs a current GL 3.3 context; binds itself on construction.
#include <cstdint>

namespace phaco::render {

class OffscreenTarget {
 public:
  // Throws RenderError when the framebuffer is incomplete.
  OffscreenTarget(int width, int height);
  ~OffscreenTarget();
  OffscreenTarget(const OffscreenTarget&) = delete;
  OffscreenTarget& operator=(const OffscreenTarget&) = delete;

  void bind() const;     // as the draw and read framebuffer
  static void unbind();  // back to the window's framebuffer
  int width() const { return width_; }
  int height() const { return height_; }

 private:
  int width_, height_;
  uint32_t fbo_ = 0, colour_ = 0, depth_stencil_ = 0;
};

}  // namespace phaco::render
