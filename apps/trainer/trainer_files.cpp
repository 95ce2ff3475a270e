#include "apps/trainer/trainer_files.hpp"

#include <epoxy/gl.h>

#include <fstream>
#include <string>

#include "engine/core/error.hpp"
#include "engine/io/tool_shape.hpp"
#include "engine/render/offscreen.hpp"

namespace phaco::trainer {

void write_json_file(const std::filesystem::path& file, const nlohmann::json& j, const char* what) {
  // Whole or not at all: a reader never sees half a file.
  const std::filesystem::path tmp = file.string() + ".tmp";
  {
    std::ofstream out(tmp);
    out << j.dump(2) << "\n";
    if (!out) throw InputError(tmp.string() + ": cannot write " + what);
  }
  std::filesystem::rename(tmp, file);
}

void save_view(render::Renderer& renderer, const render::RenderSnapshot& snap,
               const render::Microscope& microscope, int w, int h,
               const std::filesystem::path& file) {
  render::OffscreenTarget target(w, h);
  glViewport(0, 0, w, h);
  glClearColor(0.02f, 0.02f, 0.03f, 1.0f);
  glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
  renderer.draw(snap, microscope, w, h);
  render::save_screenshot(file, w, h);
  render::OffscreenTarget::unbind();
}

void write_view_poses(const std::filesystem::path& file, const render::RenderSnapshot& snap,
                      const render::Microscope& m, double sim_time_s, int w, int h) {
  const auto xyz = [](const Vec3& v) { return nlohmann::json{v.x(), v.y(), v.z()}; };
  nlohmann::json j;
  j["sim_time_s"] = sim_time_s;
  j["width"] = w, j["height"] = h;
  j["microscope"] = {{"field_mm", m.field_mm},
                     {"focus_z_mm", m.focus_z_mm},
                     {"working_distance_mm", m.working_distance_mm},
                     {"centre_mm", xyz(m.centre_mm)}};
  const Quat& g = snap.globe_rotation;
  j["globe_rotation_wxyz"] = {g.w(), g.x(), g.y(), g.z()};
  j["tools"] = nlohmann::json::array();
  for (const render::ToolView& t : snap.tools) {
    // The shaft's axis as drawn: beside the tip by a bent point (engine/io/tool_shape).
    const ShaftAxis axis = shaft_axis({t.tip_mm, t.quat, 0, 0}, t.kind);
    j["tools"].push_back({{"hand", std::string(to_string(t.hand))},
                          {"tool", std::string(to_string(t.kind))},
                          {"tip_mm", xyz(t.tip_mm)},
                          {"shaft", xyz(axis.direction)},
                          {"shaft_point_mm", xyz(axis.point)}});
  }
  write_json_file(file, j, "the view's poses");
}

}  // namespace phaco::trainer
