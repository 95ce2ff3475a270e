#include "engine/io/bounds.hpp"

#include <array>
#include <cmath>

#include "engine/io/json_reader.hpp"

namespace phaco::io {

Vec3 read_workspace_point(const JsonReader& reader, const nlohmann::json& v,
                          const std::string& path) {
  std::array<double, 3> p{};
  reader.fixed_numbers(v, path, p, "[x, y, z]");
  for (std::size_t i = 0; i < p.size(); ++i) {
    if (std::abs(p[i]) > kWorkspaceHalfMm) {
      reader.fail(path_index(path, i),
                  "expected a coordinate in " + format_number(-kWorkspaceHalfMm) + ".." +
                      format_number(kWorkspaceHalfMm) +
                      " mm (the workspace around the eye's origin), got " + format_number(p[i]));
    }
  }
  return {p[0], p[1], p[2]};
}

}  // namespace phaco::io
