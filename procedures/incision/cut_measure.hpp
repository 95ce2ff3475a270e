#pragma once
// What a keratome's cut in one corneal surface looks like on the mesh, measured from the mesh
// alone: its lips (the opened edges), its ends (the two crack tips), its middle and its distance
// to the path the tool drew (issue 4: "the cut edge stays within the snap threshold of the tool
// path (Hausdorff distance)").
//
// Lips: the edges of live triangles with no neighbour across them. The cornea shell is closed, so
// before a cut there are none; after, they are exactly the opened cut edges (and a slit's shared
// edge, from both sides). Each is given to the corneal sphere its midpoint lies nearer to.
//
// Hausdorff distance between the lips and the tool polyline (the section ends the cutter was fed,
// in order from the left end through the puncture to the right end), both taken as sets of
// segments, each sampled at sample_mm: max(max over lip points of the distance to the tool
// polyline, max over tool points of the distance to the lips). Sampling makes it exact to within
// sample_mm / 2.
//
// Reads: the cut mesh (particles, triangles, adjacency). Writes nothing. Allocates (a measurement,
// once per cut, not a frame's work).
#include <array>
#include <cstdint>
#include <vector>

#include "systems/cut/membrane_edit.hpp"
#include "systems/incision/wound.hpp"

namespace phaco::corneal_incision {

enum class Surface : uint8_t { Anterior, Posterior };

struct SurfaceCut {
  bool exists = false;               // at least one lip edge on this surface and both tips known
  uint32_t lip_edges = 0;            // triangle edges without a neighbour (both lips)
  uint32_t lip_loops = 0;            // connected pieces of the lip edges (one cut: 1)
  bool lips_closed = false;          // every lip vertex has exactly two lip edges (a loop)
  double lip_length_mm = 0;          // half their total length: the mean length of a lip
  Vec3 left_end = Vec3::Zero();      // mm, crack tip of the left path
  Vec3 right_end = Vec3::Zero();     // mm, crack tip of the right path
  double chord_mm = 0;               // |right_end − left_end|
  Vec3 middle = Vec3::Zero();        // mm, mean of the lips' crossings of the tips' bisector plane
  double lips_to_tool_mm = 0;        // directed: farthest lip point from the tool polyline
  double tool_to_lips_mm = 0;        // directed: farthest tool point from the lips
  double hausdorff_mm = 0;           // max of the two
  double max_surface_offset_mm = 0;  // max | |x − C| − R | over lip vertices, own sphere
  double min_other_surface_mm = 0;  // min | |x − C'| − R' | over lip vertices, the other sphere
  double max_radius_mm = 0;   // largest projected radius (from the optical axis) of a lip vertex
  uint32_t rim_vertices = 0;  // lip vertices at or beyond the limbus radius (rim band)
};

// Distance (mm) of p from the surface's sphere: | |p − C| − R |.
double sphere_offset(const incision::CorneaSpheres& spheres, Surface surface, const Vec3& p);

// Lip edges on `surface` as (triangle's corner, next corner) pairs, in triangle order.
void lip_edges(const cut::CutMesh& mesh, const incision::CorneaSpheres& spheres, Surface surface,
               std::vector<std::array<uint32_t, 2>>& out);

// Two-sided sampled Hausdorff distance between two sets of segments (pairs of points); also
// returns the directed parts. Empty sets give 0.
struct Hausdorff {
  double a_to_b = 0, b_to_a = 0, both = 0;
};
Hausdorff segment_hausdorff(const std::vector<std::array<Vec3, 2>>& a,
                            const std::vector<std::array<Vec3, 2>>& b, double sample_mm);

// The cut on `surface`, its ends being particles left_tip and right_tip (kInvalidIndex: unknown,
// then exists = false), compared with the polyline through tool_points. Throws
// std::invalid_argument for a sample_mm that is not finite and positive.
SurfaceCut measure_surface_cut(const cut::CutMesh& mesh, const incision::CorneaSpheres& spheres,
                               Surface surface, uint32_t left_tip, uint32_t right_tip,
                               const std::vector<Vec3>& tool_points, double sample_mm = 0.005);

}  // namespace phaco::corneal_incision
