#pragma once
// Wavefront OBJ for triangle surfaces: only `v` and `f` lines carry data. Faces may be written
// "f a b c", "f a/t/n ...", "f a//n ..." with 1-based or negative (relative) indices; polygons are
// fan-triangulated. Other statements (vn, vt, o, g, s, usemtl, mtllib) are skipped.
#include <filesystem>

#include "engine/core/mesh_data.hpp"

namespace phaco {

// Coordinates are written as the shortest text that reads back to the same double, so
// write_obj -> read_obj is exact and the same mesh always gives the same bytes.
void write_obj(const std::filesystem::path& file, const SurfaceMesh& mesh);

// Throws InputError "FILE:LINE: ..." on a missing file, a bad or non-finite number, a face with
// fewer than three corners or an index that is zero or out of range.
SurfaceMesh read_obj(const std::filesystem::path& file);

}  // namespace phaco
