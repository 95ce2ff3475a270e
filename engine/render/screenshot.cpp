// read_pixels and save_screenshot (renderer.hpp): the bound read framebuffer as RGB rows, top
// row first, and as a PNG through OpenCV.
#include <epoxy/gl.h>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include "engine/render/renderer.hpp"

namespace phaco::render {

std::vector<uint8_t> read_pixels(int width, int height) {
  std::vector<uint8_t> rgb(static_cast<size_t>(width) * height * 3);
  glPixelStorei(GL_PACK_ALIGNMENT, 1);
  glReadPixels(0, 0, width, height, GL_RGB, GL_UNSIGNED_BYTE, rgb.data());
  // GL's rows run bottom to top; images run top to bottom.
  const size_t row = static_cast<size_t>(width) * 3;
  std::vector<uint8_t> line(row);
  for (int y = 0; y < height / 2; ++y) {
    uint8_t* a = rgb.data() + y * row;
    uint8_t* b = rgb.data() + (height - 1 - y) * row;
    std::copy(a, a + row, line.data());
    std::copy(b, b + row, a);
    std::copy(line.data(), line.data() + row, b);
  }
  return rgb;
}

void save_screenshot(const std::filesystem::path& file, int width, int height) {
  std::vector<uint8_t> rgb = read_pixels(width, height);
  cv::Mat bgr(height, width, CV_8UC3);
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x) {
      const uint8_t* p = &rgb[(static_cast<size_t>(y) * width + x) * 3];
      bgr.at<cv::Vec3b>(y, x) = cv::Vec3b(p[2], p[1], p[0]);
    }
  bool ok = false;
  try {
    ok = cv::imwrite(file.string(), bgr);
  } catch (const cv::Exception& e) {
    throw RenderError("cannot write screenshot '" + file.string() + "': " + e.what());
  }
  if (!ok) throw RenderError("cannot write screenshot '" + file.string() + "'");
}

}  // namespace phaco::render
