// The crystalline lens: its closed surface and its tetrahedralisation through TetGen.
//
// The surface is the tet boundary: TetGen runs with -Y (no Steiner points on the boundary), so the
// scene can keep the lens as this surface and switch to the tets the first time a tool changes its
// topology without the two disagreeing. Surface spacing follows the tet size of the target count,
// so boundary and interior tets are of one size and the inscribed surface loses < 1 % of volume.
#include <tetgen.h>

#include <cmath>
#include <cstdio>
#include <numbers>
#include <stdexcept>
#include <string>

#include "engine/core/mesh_checks.hpp"
#include "procedures/eye/eye_geometry.hpp"
#include "procedures/eye/eye_mesh.hpp"
#include "procedures/eye/revolve.hpp"

namespace phaco::eye {
namespace {

// Surface edge / edge of a regular tet of the mean target volume. 0.8 keeps the volume the flat
// surface triangles cut off under 1 % from level 0 on (1.0 lost 1.4 % at level 0).
constexpr double kSurfaceEdgeFactor = 0.8;
// TetGen's -a bound / mean target volume: quality refinement leaves most tets well below the
// bound, so it sits above the mean; 2.0 gives +2 % to +11 % over the target at levels 0..7.
constexpr double kMaxVolumeFactor = 2.0;

double target_tet_edge(const EyeGeometry& g, const Resolution& res) {
  const double mean_volume = g.lens_volume() / res.lens_tets;
  return std::cbrt(6.0 * std::sqrt(2.0) * mean_volume);  // regular tet of that volume
}

}  // namespace

SurfaceMesh make_lens_surface(const EyeParams& params, const Resolution& res) {
  const EyeGeometry g = eye_geometry(params);
  const double a = g.lens_a, c1 = g.lens_c_anterior, c2 = g.lens_c_posterior;
  std::vector<MeridianCurve> curves;
  // Anterior pole -> equator -> posterior pole; the equator ring is shared by both halves.
  curves.emplace_back(
      [=](double t) {
        return RZ{a * std::sin(t), c1 * std::cos(t)};
      },
      0.0, std::numbers::pi / 2);
  curves.emplace_back(
      [=](double t) {
        return RZ{a * std::cos(t), -c2 * std::sin(t)};
      },
      0.0, std::numbers::pi / 2);
  const double spacing = kSurfaceEdgeFactor * target_tet_edge(g, res) * std::sqrt(3.0) / 2.0;
  SurfaceMesh mesh = revolve(profile_rings(curves, spacing), spacing);
  orient_outward(mesh);
  return mesh;
}

TetMesh make_lens_tets(const EyeParams& params, const Resolution& res) {
  const EyeGeometry g = eye_geometry(params);
  const SurfaceMesh surface = make_lens_surface(params, res);

  tetgenio in, out;
  in.firstnumber = 0;
  in.numberofpoints = static_cast<int>(surface.vertices.size());
  in.pointlist = new REAL[surface.vertices.size() * 3];
  for (size_t i = 0; i < surface.vertices.size(); ++i) {
    for (int k = 0; k < 3; ++k) in.pointlist[3 * i + k] = surface.vertices[i][k];
  }
  in.numberoffacets = static_cast<int>(surface.triangles.size());
  in.facetlist = new tetgenio::facet[surface.triangles.size()];
  for (size_t t = 0; t < surface.triangles.size(); ++t) {
    tetgenio::facet& f = in.facetlist[t];
    tetgenio::init(&f);
    f.numberofpolygons = 1;
    f.polygonlist = new tetgenio::polygon[1];
    tetgenio::init(&f.polygonlist[0]);
    f.polygonlist[0].numberofvertices = 3;
    f.polygonlist[0].vertexlist = new int[3];
    for (int k = 0; k < 3; ++k)
      f.polygonlist[0].vertexlist[k] = static_cast<int>(surface.triangles[t][k]);
  }

  // p: the input is a closed surface; q: radius-edge bound / minimum dihedral angle (the angle
  // bound removes slivers, which the radius-edge bound alone lets through); a: volume bound;
  // z: 0-based output; Y: keep the boundary as given; Q: quiet.
  const double max_volume = kMaxVolumeFactor * g.lens_volume() / res.lens_tets;
  char switches[96];
  std::snprintf(switches, sizeof switches, "pq%.3g/%.3ga%.6gzQY", kLensRadiusEdgeBound,
                kLensMinDihedralDeg, max_volume);
  try {
    tetrahedralize(switches, &in, &out);
  } catch (int code) {
    throw std::runtime_error("TetGen failed on the lens (switches '" + std::string(switches) +
                             "', error code " + std::to_string(code) + ")");
  }
  if (out.numberoftetrahedra <= 0 || out.numberofcorners < 4) {
    throw std::runtime_error("TetGen produced no tetrahedra for the lens (switches '" +
                             std::string(switches) + "')");
  }

  TetMesh mesh;
  mesh.vertices.reserve(static_cast<size_t>(out.numberofpoints));
  for (int i = 0; i < out.numberofpoints; ++i) {
    mesh.vertices.emplace_back(out.pointlist[3 * i], out.pointlist[3 * i + 1],
                               out.pointlist[3 * i + 2]);
  }
  const double nucleus2 = g.nucleus_fraction * g.nucleus_fraction;
  mesh.tets.reserve(static_cast<size_t>(out.numberoftetrahedra));
  mesh.region.reserve(static_cast<size_t>(out.numberoftetrahedra));
  for (int t = 0; t < out.numberoftetrahedra; ++t) {
    std::array<uint32_t, 4> tet{};
    for (int k = 0; k < 4; ++k) {
      tet[k] =
          static_cast<uint32_t>(out.tetrahedronlist[t * out.numberofcorners + k] - out.firstnumber);
    }
    const Vec3& p0 = mesh.vertices[tet[0]];
    const Vec3& p1 = mesh.vertices[tet[1]];
    const Vec3& p2 = mesh.vertices[tet[2]];
    const Vec3& p3 = mesh.vertices[tet[3]];
    if (tet_signed_volume(p0, p1, p2, p3) < 0.0) std::swap(tet[2], tet[3]);
    const Vec3 centroid = 0.25 * (p0 + p1 + p2 + p3);
    // The implicit function is quadratic, so "inside the lens scaled by f" is implicit <= f².
    const bool nucleus = g.lens_implicit(centroid.x(), centroid.y(), centroid.z()) <= nucleus2;
    mesh.tets.push_back(tet);
    mesh.region.push_back(nucleus ? 1 : 0);
  }
  return mesh;
}

EyeMeshes make_eye_meshes(const EyeParams& params, const Resolution& res, CapsuleLayout layout,
                          bool with_lens_tets) {
  EyeMeshes m;
  m.res = res;
  m.cornea = make_cornea(params, res);
  m.capsule = make_capsule(params, res, layout);
  m.iris = make_iris(params, res);
  m.globe = make_globe(params, res);
  m.lens_surface = make_lens_surface(params, res);
  if (with_lens_tets) m.lens_tets = make_lens_tets(params, res);
  return m;
}

}  // namespace phaco::eye
