#pragma once
// A scripted corneal incision on the cornea shell, for tests and the perf harness (issue 4 item 2;
// seed 000 §5.2 progressive cutting, §6.1 "an angled keratome ... entering the cornea at the
// limbus at a shallow angle"; seed 001 §3.3 port arc).
//
// The keratome starts on the anterior sphere at the approach's clock hour, distance from the
// limbus and entry angle (incision_start_blade) and advances straight along its axis, step_mm per
// frame. Each frame update_wound sections the blade with both corneal spheres; the sections' ends
// are the cut points (seed 000: "cut points are tool–mesh intersections sampled at regular
// intervals"). Per surface two cut paths grow from the puncture, one to each end:
//
//        left end  <-------- puncture --------> right end      (one surface, seen along n)
//        path L: c0 = puncture, then the left ends     path R: c0 = path L's c0 vertex, then the
//        right ends
//
// An end is fed only while it moves away from the puncture (the cut widens; it never heals), so
// the sides of a fully inserted blade and its withdrawal cut nothing more. Path R starts at the
// vertex path L's initial cut made of the puncture, so the two paths are one cut; its first
// segment opens that vertex's fan on both sides, duplicating it (seed 000 Fig. 4c): the wound
// gapes. The blade stops once its shoulders have passed the posterior sphere (both sections have
// the full width W on the blade's sides), every path ends (end_cut: the tool left the mesh), and
// the blade is withdrawn along its axis, the tracker still updated (the wound keeps its maxima).
//
// Reads and writes: the cut mesh (particles, triangles, springs, topology).
#include <cstdint>

#include "components/wound.hpp"
#include "procedures/incision/cut_measure.hpp"
#include "systems/cut/progressive_cut.hpp"
#include "systems/incision/keratome.hpp"
#include "systems/incision/wound.hpp"

namespace phaco::corneal_incision {

struct IncisionScript {
  incision::IncisionApproach approach;  // clock hour, distance inside the limbus, entry angle
  incision::KeratomeShape shape;        // width: eye file tools.keratome_width_mm (eye_keratome)
  double step_mm = 0.05;                // blade advance per frame
  double max_advance_mm = 0.0;          // stop here if the blade has not passed; 0: shape.length_mm
  double measure_sample_mm = 0.005;     // sampling of the Hausdorff measure
  // When the blade stops, a path whose tip waits short of its end is finished with this minimum
  // angle instead of CutSettings::min_angle_deg (if smaller; ≥ the invariants' 1°). 0: no
  // finishing.
  double finish_min_angle_deg = 2.0;
};

struct IncisionResult {
  CornealWound wound;           // the tracker's measures over the whole pass
  PortArc port;                 // seed 001 §3.3
  SurfaceCut outer;             // the cut in the anterior surface, measured on the mesh
  SurfaceCut inner;             // the cut in the posterior surface
  bool passed = false;          // the shoulders passed the posterior sphere before max_advance_mm
  double advance_mm = 0.0;      // how far the tip went
  uint32_t frames = 0;          // advancing frames (withdrawal not counted)
  uint32_t cutting_frames = 0;  // advancing frames in which a cut path changed the mesh
  uint64_t segments = 0;        // segments that changed the mesh, all four paths
  bool finished = false;        // the finishing samples changed the mesh
  double finish_ms = 0.0;       // their wall time
  uint32_t triangles_before = 0, triangles_after = 0;       // live
  uint32_t particles_before = 0, particles_after = 0;       // live
  double outer_max_snap_mm = 0.0, inner_max_snap_mm = 0.0;  // furthest snap of a cut point
  double frame_ms_mean = 0.0;  // wall time of an advancing frame's wound update and cuts
  double frame_ms_max = 0.0;
  double cutting_frame_ms_mean = 0.0;  // the same over the frames that changed the mesh
  // The wound measured on the mesh: from the outer cut's middle (and the inner's, for the angle).
  double mesh_clock_hour = 0.0;
  double mesh_limbus_distance_mm = 0.0;
  double mesh_entry_angle_deg = 0.0;   // of the line outer middle -> inner middle, below z = const
  double mesh_tunnel_length_mm = 0.0;  // |inner middle − outer middle|
};

// Throws std::invalid_argument, naming the field, before touching the mesh: a bad approach or
// blade shape (incision_start_blade's messages, e.g. "approach.entry_angle_deg", "width_mm"),
// bad spheres (check_spheres), a step_mm or max_advance_mm that is not finite and positive
// (max_advance_mm may be 0: the default), a measure_sample_mm that is not finite and positive, or
// a finish_min_angle_deg that is neither 0 nor at least 1.
IncisionResult run_scripted_incision(cut::CutMesh& mesh, const incision::CorneaSpheres& spheres,
                                     const IncisionScript& script, const cut::CutSettings& cut);

}  // namespace phaco::corneal_incision
