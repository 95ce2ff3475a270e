#pragma once
// Procedural, deterministic meshes of the standard eye (DESIGN.md §6 frame, mm). The same
// parameters and resolution always give the same vertices and triangles in the same order.
// Closed surfaces face outward; the open capsule and iris face +z (the surgeon).
#include <optional>

#include "engine/core/mesh_data.hpp"
#include "procedures/eye/eye_params.hpp"
#include "procedures/eye/resolution.hpp"

namespace phaco::eye {

enum class CapsuleLayout {
  Curvilinear,  // rings and spokes, checkerboard diagonals: interior valence 4 or 8 (seeds 003/004)
  Isotropic,    // near-equilateral triangles, interior valence about 6
};

const char* to_string(CapsuleLayout layout);

// Vertex targets of the other surfaces, as fractions of the capsule target.
constexpr double kCorneaVertexFraction = 0.5;
constexpr double kIrisVertexFraction = 0.25;
constexpr double kGlobeVertexFraction = 0.25;

// Closed shell: anterior spherical cap, posterior spherical cap and the limbus rim band.
SurfaceMesh make_cornea(const EyeParams& params, const Resolution& res);

// Open disc on the anterior lens surface out to projected radius capsule.radius_mm.
// Curvilinear: vertex 0 is the centre, then rings from the centre outward, each ring's vertices in
// increasing angle starting on +x; the last ring is the rim.
SurfaceMesh make_capsule(const EyeParams& params, const Resolution& res, CapsuleLayout layout);

// Annulus in the plane z = iris.z_mm from the pupil margin to the posterior cornea.
SurfaceMesh make_iris(const EyeParams& params, const Resolution& res);

// Closed sphere of radius globe.radius_mm, posterior pole axial_length behind the corneal apex.
SurfaceMesh make_globe(const EyeParams& params, const Resolution& res);

// Closed: anterior and posterior half-ellipsoids sharing the equator ring. Its spacing follows the
// tet target, so it is exactly the boundary of make_lens_tets.
SurfaceMesh make_lens_surface(const EyeParams& params, const Resolution& res);

// Tetrahedralises make_lens_surface with TetGen keeping that surface as the boundary (its vertices
// come first, in order), with the quality bounds below and a volume bound chosen so the count is
// near res.lens_tets. region 1 = tet centroid inside the nucleus, else 0 (cortex).
// Throws std::runtime_error if TetGen fails.
TetMesh make_lens_tets(const EyeParams& params, const Resolution& res);

// TetGen's quality bounds for the lens tets (its -q switch): circumradius / shortest edge, and the
// smallest dihedral angle. The radius-edge bound holds at levels 0..3; with the boundary fixed
// (-Y) TetGen cannot always meet it next to the surface at higher levels, and it treats the angle
// as a goal rather than a guarantee (measured figures in docs/eye_model.md).
constexpr double kLensRadiusEdgeBound = 1.5;
constexpr double kLensMinDihedralDeg = 10.0;

struct EyeMeshes {
  Resolution res;
  SurfaceMesh cornea, capsule, iris, globe, lens_surface;
  std::optional<TetMesh> lens_tets;
};

EyeMeshes make_eye_meshes(const EyeParams& params, const Resolution& res, CapsuleLayout layout,
                          bool with_lens_tets);

}  // namespace phaco::eye
