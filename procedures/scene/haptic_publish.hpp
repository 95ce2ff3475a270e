#pragma once
// Publish phase, haptic half (DESIGN.md §4 step 5, §5): per tool, the small local model the 1 kHz
// haptic thread computes force from between frames (components/haptic_model.hpp).
//
//   nodes    seed 003 §III.D: the capsule particles within k hops (haptic_model.active_hops, the
//            seed's k = 5) of what the tool holds or touches — the grasped particle, else the
//            capsule particle nearest the tip within haptic_model.contact_radius_mm — free, and
//            the next ring anchored so the set is held as the full mesh holds it. When the ball
//            would overflow the model's capacity, its last layer becomes the anchored ring.
//   springs  every capsule spring between two local nodes (Hooke; the scene's rest lengths, which
//            carry the pretension, and stiffnesses)
//   patch    capsule triangles whose three corners are local, nearest the tip first
//   lens     the standard lens's two half-ellipsoids for seed 003 §E.5's F = −k_f·d, where the
//            lens keeps its shape; a lens the tools sculpt or break (lens.model tets or fragments)
//            is published instead as spheres of its material near each tip, with the tool's held
//            fragment (procedures/scene/haptic_lens_contacts, issue 19 item 5)
//   port     the corneal port the tool is in (procedures/scene/tool_ports, when the ports are
//            measured or constrained), turned with the globe as this frame's equilibrium left it,
//            with the tunnel's stiffness (issue 20 item 2)
//
// Cost: re-binning the active set (systems/point_bins), then per tool the bins within the contact
// radius, a breadth-first walk of the ball and of its triangle fans, and a ≈ 62 KiB model write:
// what the tools touch, not the mesh (issue 17). Whole scans remain where there is no locality to
// keep: the first frame's binning, a capsule without an active set, and, with capsule.cutting off,
// the patch (no vertex-to-triangle index). Reads: tools.pose, tools.grasp, capsule.particles,
// capsule.springs, capsule.solver (the active set), capsule.settings, capsule.triangles,
// capsule.cutting, tools.held, tools.ports, lens.sculpting, lens.tets, lens.cells. Writes:
// haptics.model.
#include <cstdint>
#include <vector>

#include "components/haptic_model.hpp"
#include "engine/schedule/system.hpp"
#include "procedures/scene/haptic_lens_contacts.hpp"
#include "systems/point_bins/point_bins.hpp"

namespace phaco {

struct Scene;
struct PortsRecord;

struct HapticPublishSettings {
  uint32_t active_hops = 5;           // seed 003 §III.D
  double contact_radius_mm = 1.0;     // a tool this near the capsule takes a local model of it
  double lens_stiffness_mn_mm = 100;  // seed 003 §E.5 k_f
  double patch_stiffness_mn_mm = 200;
  HapticLensSettings lens;
};

// Scratch kept between frames so that publishing does not allocate once warm.
struct HapticPublishScratch {
  uint64_t published = 0;       // models built so far: the next one's sequence number
  std::vector<uint16_t> local;  // per capsule particle: its local index, or kHapticNoNode
  std::vector<uint32_t> nodes;  // local → capsule particle
  std::vector<uint32_t> layer, next;
  std::vector<std::pair<float, uint32_t>> near_triangles;  // squared distance to the tip, triangle
  std::vector<uint32_t> fan;                               // one node's triangles
  point_bins::PointBins bins;  // the capsule's particles, for the nearest
  HapticLensScratch lens;
  std::vector<double> tip_radius_mm;  // per scene tool (its tip sphere, mm)
};

// The settings from the eye parameters' haptic_model section.
HapticPublishSettings haptic_publish_settings(const Scene& scene);

// Fills `model` from the scene as it is now (after the frame's dynamics). Every field of every
// tool is rewritten; `sequence`, `frame`, `sim_time_s` and `published_ns` are set too.
void build_haptic_model(const Scene& scene, const HapticPublishSettings& settings,
                        HapticPublishScratch& scratch, HapticModel& model);

// The port tool `index` (scene.tools order) is in, from the ports' record, into `t`'s port_*
// fields (port_present false when it is in none).
void fill_haptic_port(const PortsRecord& ports, size_t index, HapticTool& t);

// The frame's system: builds into scene.haptics->model_slot() and publishes it.
SystemDesc haptic_publish_system(Scene& scene);

// Radius of a tool's tip as the haptic model sees it, mm (from the eye's `tools` section).
double haptic_tip_radius_mm(const Scene& scene, uint8_t tool_kind);

}  // namespace phaco
