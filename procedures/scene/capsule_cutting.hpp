#pragma once
// Cutting and tearing the anterior capsule in the running scene (issue 4): the cystotome cuts
// where its tip touches the capsule (seed 000 §5.2 progressive cut: a cut point per frame while
// in contact, the path ends when the tip leaves), and a forceps holding the flap tears it
// (systems/tear) from the tip of the last cystotome cut. Seed 000's f_t: the flap is a strip under
// tension between the forceps and the tear's tip, so the pull reaches the tip along the strip — its
// direction from the tip to the forceps, its magnitude the pull of the held particle's springs.
// The tear is the force limit (issue 17 item 5): its threshold is the capsule's tear resistance
// F_c = G_c·h/2 (systems/tear), and the held flap folds at F_c — the stretched springs at the held
// particle lengthen, for this frame, until their pull is F_c — because our membrane, unlike a real
// flap, cannot fold over and would otherwise drag the disc behind the forceps (docs/
// cutting_and_tearing.md, "Tear forces").
//
// The cut runs in the capsule's rest shape (material coordinates): the membrane under the forceps
// is stretched, sheared and folded, and a tear walked over the deformed surface meets its own
// flap. So for the edits the particle positions are swapped (O(1), vector swaps) with a mirror of
// the rest positions; the cystotome's contact point is located on the deformed capsule and carried
// to the rest shape by its barycentric weights; the tear direction is the flap force's. After the
// edits the positions are swapped back and each new particle is placed by replaying its origin
// (cut::ParticleOrigin) on the current positions.
//
// Runs in the topology phase, before the dynamics: it edits the capsule's tables through a
// CutMesh (local edits), then, if anything changed, patches the physics (capsule.springs) where
// the edits touched it: new springs are already in the force blocks' unplanned tail, removed ones
// are tombstones, the spring graph's rows of their ends are patched, the glue grows for the new
// particles. Nothing in a cut frame passes over the whole capsule. When the tail and tombstones
// pass a fraction of the spring table (compact_fraction), the next frame WITHOUT a topology change
// compacts, sorts and re-plans the springs and rebuilds the graph: a whole-capsule pass, rare and
// amortised (docs/cutting_and_tearing.md). Remeshing is off in the scene so that no particle is
// removed by the cut itself.
//
// Forceps grasp inside a triangle or on an edge through a temporary vertex (seed 000 Fig. 9,
// systems/cut/grasp_point): when a forceps closes near the capsule, the point under its tip becomes
// a vertex (in the deformed shape, where the forceps are), which systems/grasp then holds as the
// nearest particle; once the forceps have let go it is removed again if nothing has cut through it.
//
// Methods (scenario `methods`): capsule.cutting on | off (default on); capsule.tear_rule
// flap_force | most_stressed_spring (default flap_force).
#include <nlohmann/json.hpp>

#include "engine/schedule/system.hpp"
#include "procedures/scene/rim_tear.hpp"
#include "systems/cut/grasp_point.hpp"
#include "systems/cut/progressive_cut.hpp"
#include "systems/tear/tear.hpp"

namespace phaco {

struct Scene;

struct CapsuleCutting {
  cut::MembraneTopology topology;
  cut::MembraneMaterial material;
  cut::CutSettings cut;
  tear::TearSettings tear;
  double contact_mm = 0.05;     // cystotome tip this close to the capsule cuts,
  double penetration_mm = 0.5;  // and so does one pressed up to this far through it
  // A stroke ends only once the tip is this far off the capsule (tools.cystotome_tip_mm): a blade
  // lifted less than its own length is still in its hole, so a hand's tremor at the puncture or
  // along the cut does not end the stroke. Off contact but within it, the tip cuts nothing; a
  // stroke touched again further than this from where it stopped starts anew.
  double release_mm = 0.3;
  bool stroke_lifted = false;  // the stroke's tip is off contact, within release_mm
  double min_lever_mm = 0.3;   // forceps this close to the tear's tip do not tear
  uint32_t contact_hint = 0;   // where the last tool contact was located
  cut::CutPath stroke;         // the cystotome's current path
  cut::CutPath flap;           // the path the tear continues (the last stroke with a tip)
  tear::TearState tear_state;
  std::vector<float> rest_x, rest_y,
      rest_z;                            // per particle: the rest shape, swapped in for the edits
  std::vector<cut::GraspPoint> forceps;  // per scene tool: the temporary grasp vertex it holds
  // The cut's fresh lips (particles the cut made in the last source_frames frames): seeds of the
  // capsule's active set, so the dynamics open the cut wherever it is.
  std::vector<uint32_t> sources;
  std::vector<uint64_t> source_frame;
  uint64_t source_frames = 15;
  uint64_t temporary_vertices = 0, temporary_removed = 0, temporary_kept = 0;
  // The tear as the force limit (systems/tear, issue 17 item 5): threshold F_c = tear.threshold_mn,
  // from capsule.tear_energy_j_m2 and the thickness. This frame: whether the held flap pulls on an
  // open tear, its force as the tear saw it, and the steps the tear took.
  bool tearing = false;
  double flap_force_mn = 0.0;
  double held_pull_mn = 0.0;  // the held flap's pull after the fold: where the dynamics start
  uint32_t tear_steps_last_frame = 0;
  uint64_t max_tear_steps_per_frame = 0;
  // Springs (edge key) the held flap folded this frame, with their own rest lengths.
  std::vector<std::pair<uint64_t, float>> folded;
  // Tools pressing on the rhexis rim in the later steps (rim_tear.hpp): the tears they start.
  RimTears rim;
  cut::EditLog log;  // this frame's edits (cleared each frame)
  uint64_t frames = 0, cut_segments = 0, topology_changes = 0;
  double refresh_ms_total = 0.0, refresh_ms_max = 0.0;  // physics patch after changes
  // What the refreshes patched: springs added plus springs removed, summed over topology changes
  // (the touched region a refresh's cost should follow, issue 17).
  uint64_t refresh_springs_total = 0;
  // Deferred compaction: due when tail + tombstones exceed max(compact_min_springs,
  // compact_fraction × live springs); done in the next frame without topology change.
  double compact_fraction = 0.5;
  uint32_t compact_min_springs = 4096;
  uint64_t compactions = 0;
  double compaction_ms_total = 0.0;
  double edit_ms_total = 0.0, edit_ms_max = 0.0;  // the local edits themselves
};

// Adds CapsuleCutting to the capsule (after add_capsule_physics) unless methods say
// capsule.cutting = off; returns whether it did.
bool add_capsule_cutting(Scene& scene);

// The topology-phase system. Reads: tools.pose, tools.grasp, capsule.settings. Writes:
// capsule.particles, capsule.triangles, capsule.springs, capsule.cutting (this component).
SystemDesc capsule_cut_system(Scene& scene);

// For the run report: cuts, tear events, and the opening if the disc came free.
nlohmann::json capsule_cutting_summary(Scene& scene);

}  // namespace phaco
