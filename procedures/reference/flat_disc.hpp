#pragma once
// Flat circular membranes in the plane z = 0, centred on the origin, for the accuracy references:
// the same triangulations the capsule uses, laid flat so an analytic solution applies.
//
//   Curvilinear  rings and spokes with checkerboard diagonals, 8 spokes on the first ring, spokes
//                doubling where the arc between them would exceed twice the ring spacing: the
//                capsule's layout (procedures/eye/capsule.cpp), interior valence 4 or 8
//   Isotropic    the same rings with n ∝ r, zipped by angle (eye::revolve): valence about 6
//   Irregular    the isotropic mesh with every interior vertex but the centre moved by a random
//                offset (Philox, deterministic seed) uniform in a disc of 0.3 × ring spacing:
//                edge lengths spread by about ±40 %, no inverted triangle
//
// Ring spacing R/K with K chosen so the vertex count is nearest the target; vertex 0 is the
// centre; the last ring is the rim.
#include <cstdint>
#include <vector>

#include "components/particles.hpp"
#include "components/triangles.hpp"
#include "engine/core/mesh_data.hpp"

namespace phaco::reference {

enum class DiscLayout : uint8_t { Curvilinear, Isotropic, Irregular };

const char* to_string(DiscLayout layout);

struct FlatDisc {
  SurfaceMesh mesh;          // counter-clockwise seen from +z
  std::vector<uint8_t> rim;  // 1 for a rim vertex
  double radius_mm = 0.0;
  double ring_spacing_mm = 0.0;
  int rings = 0;
};

FlatDisc make_flat_disc(double radius_mm, uint32_t target_vertices, DiscLayout layout,
                        uint64_t seed = 7);

// Mean length of the mesh's edges, mm.
double mean_edge_length(const SurfaceMesh& mesh);

// Smallest signed triangle area seen from +z (negative means an inverted triangle), mm².
double min_signed_area(const SurfaceMesh& mesh);

// The disc as a body: rim anchored (inv_mass 0), interior free with the lumped mass
// areal_density·A/3 per triangle corner (kg/mm², the capsule's ρ·h by default).
struct DiscBody {
  Particles particles;
  Triangles triangles;
};

DiscBody make_disc_body(const FlatDisc& disc, double areal_density_kg_mm2 = 1.3e-8);

}  // namespace phaco::reference
