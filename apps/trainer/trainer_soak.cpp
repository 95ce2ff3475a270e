#include "apps/trainer/trainer_soak.hpp"

#include <epoxy/gl.h>

#include <fstream>
#include <sstream>

#include "engine/core/error.hpp"

namespace phaco::trainer {

double resident_mb() {
  std::ifstream in("/proc/self/status");
  std::string line;
  while (std::getline(in, line)) {
    if (line.rfind("VmRSS:", 0) == 0) {
      std::istringstream fields(line.substr(6));
      double kb = 0;
      fields >> kb;
      return kb / 1024.0;
    }
  }
  return 0;
}

void count_gl_objects(SoakSample& s, unsigned max_name) {
  s.gl_buffers = s.gl_vertex_arrays = s.gl_textures = s.gl_programs = s.gl_framebuffers = 0;
  // Drivers hand out the lowest free names, so live objects sit among the first few thousand.
  for (GLuint n = 1; n <= max_name; ++n) {
    s.gl_buffers += glIsBuffer(n) == GL_TRUE;
    s.gl_vertex_arrays += glIsVertexArray(n) == GL_TRUE;
    s.gl_textures += glIsTexture(n) == GL_TRUE;
    s.gl_programs += glIsProgram(n) == GL_TRUE;
    s.gl_framebuffers += glIsFramebuffer(n) == GL_TRUE;
  }
}

std::string next_soak_drill(const std::string& drill) {
  if (drill == "capsulorhexis") return "phaco_sculpting";
  if (drill == "phaco_sculpting") return "corneal_incision";
  return "capsulorhexis";
}

void write_soak(const std::filesystem::path& file, const std::vector<SoakSample>& samples,
                double soak_for_s) {
  nlohmann::json list = nlohmann::json::array();
  for (const SoakSample& s : samples) {
    list.push_back({{"drill_index", s.drill_index},
                    {"drill", s.drill},
                    {"wall_s", s.wall_s},
                    {"rss_mb", s.rss_mb},
                    {"gl_buffers", s.gl_buffers},
                    {"gl_vertex_arrays", s.gl_vertex_arrays},
                    {"gl_textures", s.gl_textures},
                    {"gl_programs", s.gl_programs},
                    {"gl_framebuffers", s.gl_framebuffers},
                    {"haptic_period_p99_us", s.haptic_period_p99_us},
                    {"haptic_period_max_us", s.haptic_period_max_us},
                    {"haptic_fifo", s.haptic_fifo},
                    {"render_frame_p99_ms", s.render_frame_p99_ms},
                    {"score", s.score}});
  }
  std::ofstream out(file);
  out << nlohmann::json{{"soak_for_s", soak_for_s}, {"samples", list}}.dump(2) << "\n";
  if (!out) throw InputError(file.string() + ": cannot write the soak samples");
}

}  // namespace phaco::trainer
