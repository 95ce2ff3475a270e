#pragma once
// Building blocks for axisymmetric eye surfaces: meridian curves with an arc-length table (so rings
// can be spaced evenly along the surface, not in angle, which keeps triangles even near the sharp
// lens equator), and triangulation of rings of vertices around the optical axis.
//
// A ring k of n_k vertices sits at (r_k cos φ, r_k sin φ, z_k), φ = φ0_k + 2πj/n_k. Two consecutive
// rings are joined by a strip; where the counts differ the strip is merged by angle (the "zipper"):
//
//     B:  o-----o-----o-----o-----o        each step advances whichever ring's next vertex has the
//          \   / \   /|\   / \   /         smaller angle, emitting one triangle, so a strip of
//     A:    o-----o---o-o-----o            n_A + n_B triangles results for any n_A, n_B.
//
// A ring with r = 0 is a pole: one vertex, joined to its neighbour ring by a fan.
#include <cstdint>
#include <functional>
#include <vector>

#include "engine/core/mesh_data.hpp"

namespace phaco::eye {

struct RZ {
  double r;  // projected radius, mm
  double z;  // mm
};

// A curve in the meridian half-plane, t in [t0, t1], with arc length tabulated for inversion.
class MeridianCurve {
 public:
  MeridianCurve(std::function<RZ(double)> point, double t0, double t1);

  double length() const { return arc_.back(); }
  // ∫ 2π r ds: area of the surface swept by revolving the curve.
  double swept_area() const { return area_; }
  // Parameter at arc length s from t0; t0 and t1 exactly at the ends.
  double param_at(double s) const;
  RZ point(double t) const { return point_(t); }
  RZ point_at_arc(double s) const { return point_(param_at(s)); }

 private:
  std::function<RZ(double)> point_;
  double t0_, t1_;
  std::vector<double> arc_;  // cumulative chord length at t0 + i·(t1-t0)/N
  double area_ = 0.0;
};

// Ring positions along consecutive curves (each starting where the previous ends), each curve split
// into max(1, round(length / spacing)) equal arc-length steps; shared end points appear once.
std::vector<RZ> profile_rings(const std::vector<MeridianCurve>& curves, double spacing);

struct Ring {
  RZ at;
  uint32_t count;      // vertices in the ring (1 for a pole)
  double phase;        // angle of vertex 0, rad
  uint32_t first = 0;  // index of vertex 0 in the mesh (set by add_ring)
};

// Appends the ring's vertices to the mesh and records where they start.
void add_ring(SurfaceMesh& mesh, Ring& ring);

// Triangulates the strip between rings a and b (either may be a pole). Triangles are (a_i, b_j,
// b_j+1) and (a_i, b_j, a_i+1): counter-clockwise seen from +z when b lies outside a in radius.
void join_rings(SurfaceMesh& mesh, const Ring& a, const Ring& b);

// Vertices on a ring of radius r for about equilateral triangles of edge 2/√3 · ring_spacing:
// round(2πr / edge), at least min_count; 1 for a pole (r = 0).
uint32_t ring_vertex_count(double r, double ring_spacing, uint32_t min_count);

// Rings with about equilateral triangles of edge ≈ 2/√3 · ring spacing: n = round(2πr / edge),
// at least min_count (poles: 1), odd rings rotated by half a step.
SurfaceMesh revolve(const std::vector<RZ>& rings, double ring_spacing, uint32_t min_count = 3);

// Reverses every triangle.
void flip(SurfaceMesh& mesh);

// Flips a closed mesh whose signed volume is negative, so it faces outward.
void orient_outward(SurfaceMesh& mesh);

// Flips an open mesh whose area-weighted normal points toward -z, so it faces the surgeon.
void orient_toward_plus_z(SurfaceMesh& mesh);

}  // namespace phaco::eye
