#pragma once
// What the 1 kHz haptic thread needs to compute force alone (DESIGN.md §5, seed 003 §III.C–E):
// per tool, a small local model published once per simulation frame through a triple buffer.
//
//   nodes     the active node set near the tool (seed 003: the k-hop set, a few hundred nodes)
//             plus the ring of anchored nodes that holds it, with their springs; integrated by
//             the haptic thread between frames
//   patch     surface triangles near the tool, corners given as node indices, so a proxy
//             (god-object) can be kept outside them and the triangles move with the nodes
//   grasp     the node the forceps hold, if any: it follows the tool proxy, and the user feels
//             the springs pulling it back (the flap's spring)
//   lens      the lens's shape near the tool, for seed 003's F = −k_f·d (penetration depth)
//   spheres   lens material near the tip as contact spheres (issue 19 item 5): the sculpted
//             nucleus (surface tets, or simplex cells) and loose fragments, for any tool; under
//             ultrasound the material's reaction is capped (the tip cuts through it)
//   held      a fragment held at the tip by aspiration (components/held_fragment.hpp)
//   port      the corneal port the tool is in (issue 20 item 2): its tunnel, turned with the globe
//             as the scene solved it, holds the shaft's line to its centre
//
// Fixed capacity so that a copy into the triple buffer never allocates (≈ 36 KiB per tool).
// Plain data only; systems/haptic_model computes the force, procedures/scene fills it.
#include <array>
#include <cstdint>

#include "components/held_fragment.hpp"

namespace phaco {

inline constexpr uint32_t kHapticTools = 2;           // one per hand
inline constexpr uint32_t kHapticMaxNodes = 384;      // active set (≈ 121 for k = 5) + anchors
inline constexpr uint32_t kHapticMaxSprings = 1536;   // ≈ 4 per node on the capsule's grids
inline constexpr uint32_t kHapticMaxTriangles = 256;  // contact patch
inline constexpr uint32_t kHapticMaxSpheres = 256;    // lens material near the tip
inline constexpr uint16_t kHapticNoNode = 0xFFFF;

// Free nodes move under their springs; anchored ones hold still (outside the active set, or on a
// rigid body such as the cornea); the grasped one follows the tool proxy.
enum class HapticNodeKind : uint8_t { Free = 0, Anchored = 1, Grasped = 2 };

struct HapticTool {
  bool present = false;   // false: no tool in this hand, or nothing near it; force is zero
  uint8_t tool_kind = 0;  // phaco::ToolKind as a number (kept plain so this header needs no io)
  uint8_t hand = 0;       // phaco::Hand
  float tip_radius_mm = 0.15f;
  std::array<float, 3> tip_mm{};  // tool tip where the simulation had it at publish, mm

  // Local nodes (positions and velocities at publish).
  uint32_t node_count = 0;
  std::array<float, kHapticMaxNodes> x{}, y{}, z{};     // mm
  std::array<float, kHapticMaxNodes> vx{}, vy{}, vz{};  // mm/s
  std::array<float, kHapticMaxNodes> mass{};            // kg
  std::array<HapticNodeKind, kHapticMaxNodes> kind{};

  // Springs between local nodes (Hooke, seed 003 §E.1: f = −k·dx).
  uint32_t spring_count = 0;
  std::array<uint16_t, kHapticMaxSprings> spring_i{}, spring_j{};
  std::array<float, kHapticMaxSprings> rest_mm{};
  std::array<float, kHapticMaxSprings> k_mn_per_mm{};
  // Seed 003 §E.2–3: damping and viscoelastic (viscoelastic device, OVD) forces, −(k_d + k_v)·v.
  float damping_mn_s_per_mm = 0;

  uint16_t grasped_node = kHapticNoNode;  // local index, or none
  // The held flap tears at this force (the capsule's tear resistance, systems/tear): the grasp's
  // force is bounded by it. 0: no bound (nothing held, or no flap torn yet).
  float grasp_limit_mn = 0;

  // Contact patch: triangles near the tool (corners are local node indices).
  uint32_t triangle_count = 0;
  std::array<std::array<uint16_t, 3>, kHapticMaxTriangles> triangles{};
  float patch_stiffness_mn_per_mm = 0;  // of the proxy–surface contact

  // Lens: two half-ellipsoids about `lens_centre_mm` (DESIGN.md §6), rotated by nothing (the
  // lens is axially symmetric about +z). Seed 003 §E.5: F = −k_f·d, d the penetration depth.
  bool lens_present = false;
  std::array<float, 3> lens_centre_mm{};
  float lens_equator_radius_mm = 4.7f;
  float lens_anterior_mm = 1.8f;   // half-thickness toward +z
  float lens_posterior_mm = 2.7f;  // half-thickness toward −z
  float lens_stiffness_mn_per_mm = 0;

  // Lens material near the tip (issue 19 item 5), published by procedures/scene/
  // haptic_lens_contacts for every tool: each sphere stands for one alive tet (lens.model tets)
  // or simplex cell (lens.model fragments) with an exposed face, centred at its centroid with its
  // equal-volume radius, nearest the tip first. Each pushes the tip sphere out along the line
  // between centres with its own stiffness (the nucleus harder than the cortex). Rigid between
  // publishes: the sculpting removes spheres, the fragments move them, one frame at a time.
  uint32_t sphere_count = 0;
  std::array<float, kHapticMaxSpheres> sphere_x{}, sphere_y{}, sphere_z{};  // centre, mm
  std::array<float, kHapticMaxSpheres> sphere_r{};                          // radius, mm
  std::array<float, kHapticMaxSpheres> sphere_k{};                          // mN/mm
  // The probe under ultrasound (pedal 3) cuts: the material yields, its whole reaction on the tip
  // is bounded by this force. 0: no bound (no ultrasound, or another tool).
  float cut_force_mn = 0;

  HeldFragment held;  // a fragment held at the tip, its load felt (held.held false: none)

  // The port the tool is in (procedures/scene/tool_ports; systems/tool_eye's tunnel spring): the
  // shaft's line is free across the slit's width and held by the tunnel's spring beyond it and
  // through the slit. Where the scene's globe had it turned at publish; the device's own shaft is
  // read each tick, so levering is felt at 1 kHz.
  bool port_present = false;
  std::array<float, 3> port_centre_mm{};  // middle of the tunnel, mm
  std::array<float, 3> port_axis{};       // unit, along the tunnel into the eye
  std::array<float, 3> port_width_dir{};  // unit, across the slit (along the limbus)
  float port_half_width_mm = 0;           // free either side of the centre across the slit
  float port_tunnel_length_mm = 0;        // outer to inner opening, mm
  float port_stiffness_mn_per_mm = 0;     // tool_eye.tunnel_stiffness_mn_mm
};

struct HapticModel {
  uint64_t sequence = 0;     // increases by one per publish; 0 = nothing published yet
  uint64_t frame = 0;        // simulation frame it was built from
  double sim_time_s = 0;     // s
  int64_t published_ns = 0;  // steady clock (engine/core/clock.hpp now_ns) at publish
  std::array<HapticTool, kHapticTools> tools{};
};

}  // namespace phaco
