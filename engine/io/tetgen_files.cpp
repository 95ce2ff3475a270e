#include "engine/io/tetgen_files.hpp"

#include <string>
#include <vector>

#include "engine/io/text_lines.hpp"

namespace phaco {
namespace {

std::filesystem::path with_suffix(const std::filesystem::path& base, const char* suffix) {
  return std::filesystem::path(base.string() + suffix);
}

int64_t header_count(const text::LineTokens& lines, std::string_view token, const char* what,
                     int64_t min, int64_t max) {
  const int64_t v = lines.integer(token, what);
  if (v < min || v > max) {
    lines.fail(std::string(what) + " " + std::to_string(v) + " outside [" + std::to_string(min) +
               ", " + std::to_string(max) + "]");
  }
  return v;
}

}  // namespace

void write_tetgen(const std::filesystem::path& base, const TetMesh& mesh) {
  std::string node;
  node.reserve(mesh.vertices.size() * 72 + 32);
  text::append_number(node, static_cast<uint64_t>(mesh.vertices.size()));
  node += " 3 0 0\n";
  for (size_t i = 0; i < mesh.vertices.size(); ++i) {
    text::append_number(node, static_cast<uint64_t>(i + 1));
    for (int k = 0; k < 3; ++k) {
      node += ' ';
      text::append_number(node, mesh.vertices[i][k]);
    }
    node += '\n';
  }
  text::write_file(with_suffix(base, ".node"), node);

  std::string ele;
  ele.reserve(mesh.tets.size() * 48 + 32);
  text::append_number(ele, static_cast<uint64_t>(mesh.tets.size()));
  ele += " 4 1\n";
  for (size_t i = 0; i < mesh.tets.size(); ++i) {
    text::append_number(ele, static_cast<uint64_t>(i + 1));
    for (uint32_t v : mesh.tets[i]) {
      ele += ' ';
      text::append_number(ele, static_cast<uint64_t>(v) + 1);
    }
    ele += ' ';
    text::append_number(ele, static_cast<uint64_t>(i < mesh.region.size() ? mesh.region[i] : 0));
    ele += '\n';
  }
  text::write_file(with_suffix(base, ".ele"), ele);
}

TetMesh read_tetgen(const std::filesystem::path& base) {
  constexpr int64_t kMaxCount = 0xffffffffLL;  // indices are 32-bit
  TetMesh mesh;
  int64_t first = 0;

  {
    const auto file = with_suffix(base, ".node");
    text::LineTokens lines(file, text::read_file(file));
    if (!lines.next_nonempty())
      lines.fail("empty .node file (expected '<#points> 3 <#attributes> <#markers>')");
    const auto& h = lines.tokens();
    const int64_t n = header_count(lines, h[0], "point count", 0, kMaxCount);
    if (h.size() > 1 && lines.integer(h[1], "dimension") != 3) lines.fail("dimension must be 3");
    const int64_t attributes =
        h.size() > 2 ? header_count(lines, h[2], "attribute count", 0, 1000) : 0;
    const int64_t markers =
        h.size() > 3 ? header_count(lines, h[3], "boundary marker count", 0, 1) : 0;
    const size_t columns = static_cast<size_t>(4 + attributes + markers);
    mesh.vertices.reserve(static_cast<size_t>(n));
    for (int64_t i = 0; i < n; ++i) {
      if (!lines.next_nonempty()) {
        lines.fail("file ends after " + std::to_string(i) + " of " + std::to_string(n) + " points");
      }
      const auto& t = lines.tokens();
      if (t.size() < columns) {
        lines.fail("point line needs " + std::to_string(columns) + " columns, has " +
                   std::to_string(t.size()));
      }
      const int64_t index = lines.integer(t[0], "point index");
      if (i == 0) {
        if (index != 0 && index != 1)
          lines.fail("numbering must start at 0 or 1, not " + std::to_string(index));
        first = index;
      } else if (index != first + i) {
        lines.fail("point index " + std::to_string(index) + " out of sequence (expected " +
                   std::to_string(first + i) + ")");
      }
      mesh.vertices.emplace_back(lines.finite(t[1], "x"), lines.finite(t[2], "y"),
                                 lines.finite(t[3], "z"));
    }
    if (lines.next_nonempty()) lines.fail("more points than the header's " + std::to_string(n));
  }

  {
    const auto file = with_suffix(base, ".ele");
    text::LineTokens lines(file, text::read_file(file));
    if (!lines.next_nonempty()) lines.fail("empty .ele file (expected '<#tets> 4 <#attributes>')");
    const auto& h = lines.tokens();
    const int64_t m = header_count(lines, h[0], "tet count", 0, kMaxCount);
    const int64_t corners = h.size() > 1 ? lines.integer(h[1], "nodes per tet") : 4;
    if (corners != 4 && corners != 10) lines.fail("nodes per tet must be 4 or 10");
    const int64_t attributes =
        h.size() > 2 ? header_count(lines, h[2], "attribute count", 0, 1000) : 0;
    const size_t columns = static_cast<size_t>(1 + corners + attributes);
    const auto count = static_cast<int64_t>(mesh.vertices.size());
    mesh.tets.reserve(static_cast<size_t>(m));
    mesh.region.reserve(static_cast<size_t>(m));
    for (int64_t i = 0; i < m; ++i) {
      if (!lines.next_nonempty()) {
        lines.fail("file ends after " + std::to_string(i) + " of " + std::to_string(m) + " tets");
      }
      const auto& t = lines.tokens();
      if (t.size() < columns) {
        lines.fail("tet line needs " + std::to_string(columns) + " columns, has " +
                   std::to_string(t.size()));
      }
      std::array<uint32_t, 4> tet{};
      for (int k = 0; k < 4; ++k) {
        const int64_t v = lines.integer(t[1 + k], "tet node") - first;
        if (v < 0 || v >= count) {
          lines.fail("tet node " + std::to_string(v + first) + " out of range (" +
                     std::to_string(count) + " points numbered from " + std::to_string(first) +
                     ")");
        }
        tet[k] = static_cast<uint32_t>(v);
      }
      mesh.tets.push_back(tet);
      uint8_t region = 0;
      if (attributes > 0) {
        const double r = lines.finite(t[1 + corners], "region");
        if (r < 0 || r > 255 || r != static_cast<double>(static_cast<int>(r))) {
          lines.fail("region must be an integer in [0, 255]");
        }
        region = static_cast<uint8_t>(r);
      }
      mesh.region.push_back(region);
    }
    if (lines.next_nonempty()) lines.fail("more tets than the header's " + std::to_string(m));
  }
  return mesh;
}

}  // namespace phaco
