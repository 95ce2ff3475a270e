#pragma once
// TetGen's .node / .ele text formats, so meshes can be cached on disk and opened in TetView or
// converted by other tools. The .ele file carries one attribute column: the tet's region.
#include <filesystem>

#include "engine/core/mesh_data.hpp"

namespace phaco {

// Writes base.node and base.ele (1-based numbering, as TetGen itself writes). Coordinates use
// the shortest exact text, so write -> read is exact.
void write_tetgen(const std::filesystem::path& base, const TetMesh& mesh);

// Reads base.node and base.ele. Numbering may start at 0 or 1 (taken from the first node, as TetGen
// does). Extra node attributes and boundary markers are skipped; ten-node (second-order) tets keep
// their four corners; the first tet attribute, if any, is the region (an integer 0..255).
// Throws InputError "FILE:LINE: ..." on a missing file, a bad number or an index out of range.
TetMesh read_tetgen(const std::filesystem::path& base);

}  // namespace phaco
