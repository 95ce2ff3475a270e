#pragma once
// The mesh edges a cut segment crosses (seed 000 §5.2: "a cut segment is a straight line joining
// two consecutive cut points"; a segment over more than two triangles "is decomposed into" the
// one- and two-triangle cases of Table 1, which needs exactly this ordered list).
//
// The segment is followed on the surface: inside each triangle the target cut point is projected
// onto the triangle's plane and the walk leaves through the edge that straight line meets first,
// then continues in the neighbour across it. On a flat mesh this is the exact straight segment;
// on the curved capsule it is the surface path that keeps heading for the target. An exit point
// within vertex_snap_mm of a corner is reported once, as a Vertex crossing (the seed's proximity
// snap for "intersection points between a cut segment and the mesh"), and the walk continues
// around that vertex's fan in the triangle the direction enters; a segment along an edge is
// thus the chain of vertices on it.
//
// Reads: <body>.particles (x, y, z), <body>.triangles, the adjacency. Writes the SegmentTrace.
#include <cstdint>
#include <vector>

#include "systems/cut/cut_point.hpp"

namespace phaco::cut {

struct Crossing {
  enum Kind { Edge, Vertex } kind = Edge;
  uint32_t a = kInvalidIndex;    // Edge: first end (a < b); Vertex: the vertex
  uint32_t b = kInvalidIndex;    // Edge: second end; Vertex: kInvalidIndex
  double t = 0.0;                // Edge: position = (1-t)·x_a + t·x_b, in (0, 1)
  double s = 0.0;                // where along the chord from -> to (0..1) the crossing lies
  Vec3 position = Vec3::Zero();  // mm
};

struct SegmentTrace {
  std::vector<Crossing> crossings;  // in order from `from` to `to`, endpoints excluded
  std::vector<uint32_t> triangles;  // triangles the path passes through, in order
  bool complete = false;  // false: the path left the mesh at the rim (or could not progress)
                          // before reaching `to`; crossings then stop at the rim
  std::vector<uint32_t> scratch;  // vertex fans during the walk, kept for reuse
  void clear() {
    crossings.clear();
    triangles.clear();
    complete = false;
  }
};

// Traces the cut segment between two cut points of the same mesh (as locate_cut_point gives
// them). Throws std::invalid_argument for points with non-finite positions or a triangle that is
// dead or out of range. `out` is cleared first; no allocation once its vectors have capacity.
void trace_segment(const Particles& particles, const Triangles& triangles,
                   const TriangleAdjacency& adjacency, const CutPoint& from, const CutPoint& to,
                   const SnapSettings& snap, SegmentTrace& out);

SegmentTrace trace_segment(const Particles& particles, const Triangles& triangles,
                           const TriangleAdjacency& adjacency, const CutPoint& from,
                           const CutPoint& to, const SnapSettings& snap);

}  // namespace phaco::cut
