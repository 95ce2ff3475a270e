#include "engine/io/mesh_obj.hpp"

#include <string>
#include <string_view>
#include <vector>

#include "engine/io/text_lines.hpp"

namespace phaco {

void write_obj(const std::filesystem::path& file, const SurfaceMesh& mesh) {
  std::string out;
  out.reserve(mesh.vertices.size() * 64 + mesh.triangles.size() * 24 + 64);
  out += "# OpenPhaco surface: ";
  text::append_number(out, static_cast<uint64_t>(mesh.vertices.size()));
  out += " vertices, ";
  text::append_number(out, static_cast<uint64_t>(mesh.triangles.size()));
  out += " triangles (mm)\n";
  for (const Vec3& v : mesh.vertices) {
    out += "v ";
    text::append_number(out, v.x());
    out += ' ';
    text::append_number(out, v.y());
    out += ' ';
    text::append_number(out, v.z());
    out += '\n';
  }
  for (const auto& t : mesh.triangles) {
    out += 'f';
    for (uint32_t i : t) {
      out += ' ';
      text::append_number(out, static_cast<uint64_t>(i) + 1);
    }
    out += '\n';
  }
  text::write_file(file, out);
}

SurfaceMesh read_obj(const std::filesystem::path& file) {
  SurfaceMesh mesh;
  text::LineTokens lines(file, text::read_file(file));
  std::vector<uint32_t> corners;
  while (lines.next_nonempty()) {
    const auto& tok = lines.tokens();
    if (tok[0] == "v") {
      if (tok.size() < 4) lines.fail("vertex needs three coordinates");
      mesh.vertices.emplace_back(lines.finite(tok[1], "x"), lines.finite(tok[2], "y"),
                                 lines.finite(tok[3], "z"));
    } else if (tok[0] == "f") {
      if (tok.size() < 4) lines.fail("face needs at least three corners");
      corners.clear();
      for (size_t k = 1; k < tok.size(); ++k) {
        // Only the position index matters; "a/b/c" and "a//c" keep the part before the slash.
        const std::string_view index_text = tok[k].substr(0, tok[k].find('/'));
        const int64_t raw = lines.integer(index_text, "face index");
        const auto count = static_cast<int64_t>(mesh.vertices.size());
        const int64_t index = raw > 0 ? raw - 1 : count + raw;  // negative: relative to the end
        if (raw == 0 || index < 0 || index >= count) {
          lines.fail("face index " + std::to_string(raw) + " out of range (" +
                     std::to_string(count) + " vertices defined so far)");
        }
        corners.push_back(static_cast<uint32_t>(index));
      }
      for (size_t k = 1; k + 1 < corners.size(); ++k) {
        mesh.triangles.push_back({corners[0], corners[k], corners[k + 1]});
      }
    }
  }
  return mesh;
}

}  // namespace phaco
