#pragma once
// Progressive surface cutting, seed 000 §5.2: cut points sampled from the tool at regular
// intervals, joined by cut segments into a cut path that grows until the tool leaves the mesh.
//
// The first segment of a path is an initial cut (IC): both its cut points are new. Its first point
// becomes a mesh vertex (a face split if it lies inside a triangle, an edge split if on an edge,
// nothing if at a vertex); from then on the path always continues from a vertex, the current cut
// point c_t, so every later segment is a subsequent cut (SC) — Table 1's last row: "since SC
// always begins from a mesh vertex, the corresponding algorithms are the same as that of the
// ICs". A segment over several triangles is decomposed as the seed says, into steps that each
// cross one triangle from the vertex c_t: the step ends inside that triangle (split in three), on
// the edge opposite c_t (split in two, with its neighbour) or at a corner (no split). After each
// step the new path edge is opened (membrane_edit: open_edge), which duplicates c_t into c_t' once
// it has a cut on both sides (Fig. 4c) and splits the springs crossing the path.
//
// Snapping (the seed's proximity check): a cut point within snap.vertex_snap_mm of a vertex is
// that vertex, one within snap.edge_snap_mm of an edge lies on it; and a split that would leave a
// triangle with an angle under min_angle_deg (in the current or the rest shape) is refused and
// the point goes to the nearest edge or corner instead — so no cut can create the slivers that
// break the invariants (systems/topology_check), whatever path a trainee draws.
//
// After each segment the triangle pairs along the new path edges are merged where the path runs
// nearly straight (Fig. 5a, remesh_max_turn_deg), and springs and masses are refreshed around the
// edit. The cut-path vertices on both lips are collected as force-propagation sources.
//
// Reads and writes: <body>.particles, <body>.triangles, <body>.springs, the MembraneTopology,
// the CutPath.
#include <array>
#include <cstdint>
#include <string_view>
#include <vector>

#include "systems/cut/membrane_edit.hpp"

namespace phaco::cut {

// Seed 000 Table 1: rows c_t, columns c_{t+1}; an SC starts at a vertex.
enum class CutCase : uint8_t { IC1, IC2, IC3, IC4, IC5, IC6, SC1, SC2, SC3 };
inline constexpr int kCutCases = 9;
std::string_view to_string(CutCase c);
// IC1 face-face, IC2 edge-edge, IC3 vertex-vertex, IC4 face-edge, IC5 face-vertex, IC6 edge-vertex
// (either order); SC1/SC2/SC3: from a vertex to a face, edge or vertex.
CutCase classify_cut(CutPoint::Kind from, CutPoint::Kind to, bool subsequent);

struct CutSettings {
  SnapSettings snap;
  double min_angle_deg = 5.0;         // no split may make a smaller angle (invariants ask ≥ 1°)
  bool remesh = true;                 // Fig. 5a merging along the path
  double remesh_max_turn_deg = 10.0;  // "almost co-linear" cut edges
  uint32_t max_steps_per_segment = 4096;
  uint32_t own_lip_hops = 12;  // a boundary this close to the tip along free edges is the
                               // cut's own lip, not a boundary to cut through to
  // A blade's width: a sample behind the tip within this distance of the slit is the blade sliding
  // back in it (a hand's tremor), and the path waits instead of cutting a sliver beside its own
  // slit. 0: off.
  double slit_mm = 0.0;
  // The hole a blade's puncture leaves: the initial cut waits until the blade is this far from it,
  // so that a tremor there does not set the cut's direction. 0: off (the vertex snap only).
  double puncture_mm = 0.0;
};

struct CutPath {
  bool started = false;           // a first cut point is known
  CutPoint first;                 // c_0, until the initial cut makes it a vertex
  uint32_t tip = kInvalidIndex;   // c_t as a mesh vertex, once the initial cut is made
  Vec3 direction = Vec3::Zero();  // unit direction of the last segment made (ĉ_t)
  uint32_t hint_triangle = 0;     // where to start locating the next point
  bool reached_boundary = false;  // the path met the rim or an earlier cut: it is through
  uint32_t segments = 0;          // segments that changed the mesh
  double max_snap_mm = 0.0;       // the furthest any cut point was moved by snapping
  std::vector<Vec3> tool_points;  // every sample the path was cut toward
  std::vector<uint32_t> sources;  // cut-path particles, both lips (may include removed ones)
  std::array<uint32_t, kCutCases> case_counts{};
  std::array<uint32_t, 4> span_counts{};  // segments spanning 0, 1, 2, ≥3 triangles
};

struct SegmentReport {
  CutCase cut_case = CutCase::IC1;
  bool made = false;  // the mesh changed
  uint32_t triangles_spanned = 0;
  uint32_t steps = 0;             // one-triangle steps of the decomposition
  bool reached_boundary = false;  // the path ended on the rim or an earlier cut
  bool stalled = false;           // no way on toward the point (e.g. it lies across an opened cut)
};

// Extends the path toward the tool's sample (its nearest surface point). The first sample of a
// path only records c_0. Throws std::invalid_argument for a non-finite point. After the path has
// reached a boundary, further samples are ignored until end_cut.
SegmentReport cut_towards(CutMesh& mesh, CutPath& path, const Vec3& tool_point,
                          const CutSettings& settings, EditLog& log);

// The tool left the mesh: the next sample starts a new path (a new initial cut).
void end_cut(CutPath& path);

// The tool has stopped or is leaving, so no later sample will come for a path whose tip waits short
// of its last sample (every placement there was refused by the quality snap). The path gets that
// sample again, first with min_angle_deg as the quality bound (≥ 1°, the invariants' bound);
// if it still waits, with a vertex snap just under its gap, so the end goes to a vertex nearer the
// sample than the tip is, if one is in the way (the cut may then pass the sample by less than it
// would have fallen short). Returns true if the mesh changed; call before end_cut.
bool finish_cut(CutMesh& mesh, CutPath& path, const CutSettings& settings, double min_angle_deg,
                EditLog& log);

}  // namespace phaco::cut
