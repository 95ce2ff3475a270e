#pragma once
// What the trainer's renderer draws (issue 8; DESIGN.md §5): a plain copy of the scene's visible
// state, written by the simulation thread at the end of a frame and read by the render thread
// through a triple buffer (engine/haptics/triple_buffer.hpp), so a slow renderer never slows the
// simulation. Eye frame and units of DESIGN.md §6 (mm; +z toward the surgeon, +y 12 o'clock).
//
// The vectors are sized once and reused: the simulation thread overwrites them in place (it
// allocates only when a body's element count grows, i.e. when its topology changed).
#include <array>
#include <cstdint>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include "engine/core/math.hpp"
#include "engine/io/scenario.hpp"

namespace phaco::render {

// How a body looks (one shader path each).
enum class Look : uint8_t {
  Sclera,        // the globe: white, textured vessels
  Iris,          // textured, with the pupil as its hole
  Cornea,        // translucent, specular
  Capsule,       // thin translucent membrane; its open (cut) edges drawn as a line
  LensSurface,   // the lens seen through the pupil: lit from behind (red reflex)
  LensInterior,  // exposed tetrahedra / simplex boundary of the sculpted nucleus
};

struct BodyView {
  std::string name;  // "capsule", "lens", ... (for the UI and tests)
  Look look = Look::Capsule;
  std::vector<float> xyz;         // 3 per vertex, mm
  std::vector<uint32_t> tris;     // 3 per triangle, indices into xyz / 3
  std::vector<uint32_t> edges;    // 2 per open (cut or rim) edge to outline; may be empty
  uint64_t topology_version = 0;  // changes whenever tris/edges change: re-upload indices then
  // Lens looks only (issue 19 item 4). How much each mm of this lens dims the red reflex seen
  // through it (1/mm; 0 = a clear lens, the reflex as bright as the fundus gives it): a cataract's
  // nucleus, the harder the darker, so the reflex brightens where sculpting thinned it.
  float reflex_attenuation_per_mm = 0;
  // Per vertex, which piece of a fragmented lens it belongs to (the fragment's id, wrapped to a
  // byte; the shader tints pieces apart); empty = one piece.
  std::vector<uint8_t> piece;
};

// The tissue under a tool's tip, for the trainer's depth cue (issue 24 item 2).
enum class Tissue : uint8_t { None, Cornea, Capsule, Lens };

struct ToolView {
  ToolKind kind = ToolKind::Forceps;
  Hand hand = Hand::Right;
  Vec3 tip_mm = Vec3::Zero();
  Quat quat = Quat::Identity();  // shaft = local +z rotated by quat
  double grip = 0;               // 0 open .. 1 closed (forceps jaws)
  double pedal = 0;              // 0..3 (the phaco tip glows at 3: ultrasound on)
  bool selected = false;         // the hand the mouse drives (mouse/keyboard input)
  bool in_contact = false;       // touching tissue (drawn with a contact ring)
  // The tip's height above the tissue under it along the view axis, mm (< 0: that deep in it);
  // NaN over no tissue (procedures/trainer/tip_height.hpp).
  double height_mm = std::numeric_limits<double>::quiet_NaN();
  Tissue under = Tissue::None;
};

// Guidance cues drawn as overlays (seed 000 Fig. 8; the drill file's guidance, docs/drills.md).
struct GuidanceView {
  std::optional<Vec3> grasp_site_mm, puncture_site_mm;
  std::optional<Vec3> rhexis_centre_mm;
  double rhexis_diameter_mm = 0;
  std::optional<Vec3> trench_centre_mm;
  double trench_first_angle_deg = 0, trench_arm_mm = 0;
  std::vector<Vec3> ports_mm;  // port centres on the cornea
};

struct RenderSnapshot {
  uint64_t frame = 0;
  double time_s = 0;
  std::vector<BodyView> bodies;  // drawn opaque first, translucent (cornea, capsule) last
  std::vector<ToolView> tools;
  GuidanceView guidance;
  bool show_guidance = true;
  Quat globe_rotation = Quat::Identity();  // the whole eye turned by the ports (tool_ports)
};

}  // namespace phaco::render
