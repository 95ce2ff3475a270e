#pragma once
// Cutting the cornea in the running scene (issue 7, the corneal-incision drill; seed 000 §5.2
// progressive cut, §6.1 "an angled keratome ... entering the cornea at the limbus at a shallow
// angle"; seed 001 §3.3 port arc). When the scene has a cornea and a keratome hand, the cornea body
// becomes a cuttable membrane (procedures/incision/cornea_sheet's material, the scene's own
// particles and triangles plus springs and topology kept here) and a topology-phase system cuts it
// each frame from the keratome's pose, as procedures/incision/scripted_incision does for a scripted
// pass:
//
//   blade     = blade_from_tool_pose(ToolState, eye_keratome(params))   (tip = pos, d = −q·ẑ)
//   sections  = update_wound(tracker, blade, spheres)  (both corneal spheres, the wound's maxima)
//   per surface, two cut paths grow from the puncture to the section's left and right ends; an end
//   is fed only while it moves away from the puncture (the cut widens, it never heals).
//
// The blade stops cutting when it withdraws (its tip 0.1 mm behind the furthest it reached along
// its axis: less is hand tremor) or leaves the anterior sphere: waiting path ends are finished
// (cut::finish_cut), the crack tips kept, the paths ended. One incision per run: a second pass is
// not cut (the wound tracker still follows it). Only keratomes cut the cornea; the cornea's
// particles stay anchored (no corneal dynamics).
//
// Measured at the end (incision_metrics), on the mesh (cut_measure): width = the outer cut's chord;
// clock hour and limbus distance of the outer cut's middle; tunnel length = |inner middle − outer
// middle|; entry angle = angle of that tunnel below the anterior surface's tangent plane at the
// outer middle (the angle that sets the tunnel length: ≈ limbal thickness / sin angle); and
// complete = the blade entered the anterior chamber (the tracker's `penetrated`).
//
// Reads: tools.pose. Writes: cornea.particles, cornea.triangles, cornea.cutting (its own
// CorneaCutting record). The cut allocates (paths grow); a frame without a cut does not. No frame
// passes over the whole cornea: the puncture's start triangle comes from a grid of the cornea's
// triangles built at setup (cut::TriangleGrid), not from a scan.
#include <cstdint>

#include "components/springs.hpp"
#include "components/wound.hpp"
#include "engine/ecs/world.hpp"
#include "engine/schedule/system.hpp"
#include "procedures/eye/eye_params.hpp"
#include "procedures/incision/surface_cutter.hpp"
#include "systems/cut/progressive_cut.hpp"
#include "systems/incision/keratome.hpp"
#include "systems/incision/wound.hpp"

namespace phaco {

struct Scene;
struct DrillReport;

struct CorneaCutting {
  incision::CorneaSpheres spheres;
  incision::KeratomeShape shape;
  Springs springs;
  cut::MembraneTopology topology;
  cut::MembraneMaterial material;
  cut::CutSettings cut;
  double finish_min_angle_deg = 2.0;  // as IncisionScript: waiting ends finished at this angle
  Entity keratome;                    // the (first) keratome hand
  incision::WoundTracker tracker;
  corneal_incision::SurfaceCutter outer, inner;
  bool cutting = false;  // the blade has punctured the anterior surface and still advances
  bool done = false;     // the paths have ended (the blade withdrew or left the cornea)
  bool have_last_tip = false;
  Vec3 last_tip = Vec3::Zero();  // while cutting: the furthest along the blade; before: the last
  cut::EditLog log;
  cut::TriangleGrid grid;  // the uncut cornea's triangles by place: the puncture's start, no scan
  uint64_t frames = 0, cutting_frames = 0, segments = 0;
  double edit_ms_total = 0.0, edit_ms_max = 0.0;
};

// Adds CorneaCutting to the cornea when the scene has a cornea body and a keratome hand; returns
// whether it did.
bool add_cornea_cutting(Scene& scene);

// The topology-phase system: reads tools.pose, writes cornea.particles, cornea.triangles and
// cornea.cutting (this record).
SystemDesc cornea_cut_system(Scene& scene);

// The incision's metrics and lip series (targets: data/drills/corneal_incision.json)
// (docs/metrics.md, "Corneal incision"); metrics of a cut that does not exist are left out (they
// then score 0). Call at the end of the run.
void incision_metrics(Scene& scene, DrillReport& out);

// The wound measured on the mesh (for tests and incision_metrics): false if the scene has no
// CorneaCutting.
struct MeshIncision {
  bool complete = false;   // the blade entered the anterior chamber
  bool outer_cut = false;  // a cut exists on the anterior surface (both tips known)
  bool inner_cut = false;
  double width_mm = 0, clock_hour = 0, limbus_distance_mm = 0;
  double entry_angle_deg = 0;       // below the anterior surface's tangent plane
  double iris_plane_angle_deg = 0;  // below the iris plane (IncisionResult::mesh_entry_angle_deg)
  double tunnel_length_mm = 0;
  // The middles of the outer and inner cuts (mm): the tunnel runs from one to the other.
  Vec3 outer_middle = Vec3::Zero(), inner_middle = Vec3::Zero();
  CornealWound wound;  // the tracker's (section-based) measures
};
bool measure_scene_incision(Scene& scene, MeshIncision& out);

}  // namespace phaco
