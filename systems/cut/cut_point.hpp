#pragma once
// Cut points on a triangulated membrane (seed 000 §5.2, Table 1): where a tool sample lands on the
// surface, classified as inside a triangle, on an edge or at a vertex, after the proximity snap
// of the seed ("if a point is too close to a vertex it is snapped to that vertex; if its
// perpendicular distance to an edge is below a threshold it is snapped to the edge").
//
// Geometry only: nothing here changes a mesh. The topology change (Table 1's IC/SC algorithms)
// consumes these points later.
//
// Locating walks from a start triangle (the previous cut point's, so the cost is local) to the
// triangle whose closest point to the sample is nearest, always moving to a strictly closer
// neighbour (across an edge, or around a vertex fan), so it cannot cycle; if the start is unusable
// or the walk exceeds the triangle count it falls back to a scan of all live triangles.
// The result is canonical: the same sample gives the same CutPoint from any start triangle
// (edge ends ordered a < b, the triangle the lowest index holding the feature).
//
// Reads: <body>.particles (x, y, z), <body>.triangles. Writes nothing.
#include <array>
#include <cstdint>
#include <vector>

#include "components/particles.hpp"
#include "components/triangles.hpp"
#include "engine/core/handle.hpp"
#include "engine/core/math.hpp"

namespace phaco::cut {

// Neighbour of triangle t across its edge k, where edge 0 = (a,b), 1 = (b,c), 2 = (c,a);
// kInvalidIndex on the rim, for dead triangles and across non-manifold edges (> 2 triangles).
struct TriangleAdjacency {
  std::vector<std::array<uint32_t, 3>> neighbour;
};

// Built once per topology (O(T log T), deterministic). Throws std::invalid_argument if a live
// triangle refers to a particle index >= particle_count or repeats a vertex.
TriangleAdjacency build_triangle_adjacency(const Triangles& triangles, uint32_t particle_count);

struct SnapSettings {
  double vertex_snap_mm = 0.02;  // surface point within this of a vertex -> that vertex
  double edge_snap_mm = 0.01;    // else within this of an edge -> that edge
};

struct CutPoint {
  enum Kind { Face, Edge, Vertex } kind = Face;
  uint32_t triangle = kInvalidIndex;  // lowest-index live triangle holding the feature
  uint32_t a = kInvalidIndex;         // Edge: first end (a < b); Vertex: the vertex
  uint32_t b = kInvalidIndex;         // Edge: second end; else kInvalidIndex
  double t = 0.0;                     // Edge: position = (1-t)·x_a + t·x_b
  Vec3 bary = Vec3::Zero();           // weights of (triangles.a, b, c)[triangle] giving position
  Vec3 position = Vec3::Zero();       // mm, on the surface, after snapping
  double distance_mm = 0.0;           // |point - position|
};

// The surface point nearest `point`, classified and snapped. Throws std::invalid_argument on a
// non-finite point, negative or non-finite snap thresholds, an adjacency of the wrong size or a
// mesh without live triangles; start_triangle may be anything (dead or out of range -> scan).
CutPoint locate_cut_point(const Particles& particles, const Triangles& triangles,
                          const TriangleAdjacency& adjacency, uint32_t start_triangle,
                          const Vec3& point, const SnapSettings& snap);

// Triangles binned by centroid in a uniform grid, built once (O(n), at scene setup) so that the
// first contact of a tool — where there is no walk hint yet — finds its start triangle from the
// few cells round the point instead of scanning every triangle inside a frame. Triangles a cut
// adds later are not binned; the grid only seeds locate_cut_point's walk.
struct TriangleGrid {
  Vec3 origin = Vec3::Zero();
  double cell_mm = 1.0;
  std::array<uint32_t, 3> dims{0, 0, 0};
  std::vector<uint32_t>
      cell_begin;  // per cell + 1: triangles of cell c are [cell_begin[c], cell_begin[c+1])
  std::vector<uint32_t> triangles;
};

// Cells about twice the mean edge length.
TriangleGrid build_triangle_grid(const Particles& particles, const Triangles& triangles);

// The alive binned triangle nearest `point` (by the distance to its closest point, lowest index
// on ties) among the cells within one cell of the point's; kInvalidIndex if those are empty or
// the point is outside the grid's box by more than a cell (callers then fall back to the scan).
uint32_t nearest_binned_triangle(const TriangleGrid& grid, const Particles& particles,
                                 const Triangles& triangles, const Vec3& point);

// Live triangles around `vertex` reachable from `triangle` (which must hold it) across edges
// through the vertex, sorted by index. Cleared first; no allocation once `out` has capacity.
void vertex_fan(const Triangles& triangles, const TriangleAdjacency& adjacency, uint32_t triangle,
                uint32_t vertex, std::vector<uint32_t>& out);

// Position of the particle, in double.
inline Vec3 particle_position(const Particles& p, uint32_t i) {
  return Vec3(p.x[i], p.y[i], p.z[i]);
}

// Corner k (0, 1, 2) of triangle t.
inline uint32_t corner(const Triangles& tr, uint32_t t, int k) {
  return k == 0 ? tr.a[t] : (k == 1 ? tr.b[t] : tr.c[t]);
}

// Barycentric weights (of corners a, b, c) of q projected on the plane of triangle T; false if T
// is degenerate.
bool projected_bary(const Particles& p, const Triangles& tr, uint32_t T, const Vec3& q, Vec3& w);

// Walking in barycentric weights from `from` straight toward `target`: how far (in units of the
// whole way) the line stays inside the triangle, infinity if the target is inside; `exit` is the
// corner whose weight reaches 0 first (the line leaves across the edge opposite it), -1 if none.
double exit_parameter(const Vec3& from, const Vec3& target, int& exit);

// Which corner (0, 1, 2) of triangle t is particle v; -1 if none.
inline int corner_slot(const Triangles& tr, uint32_t t, uint32_t v) {
  for (int k = 0; k < 3; ++k)
    if (corner(tr, t, k) == v) return k;
  return -1;
}

}  // namespace phaco::cut
