#pragma once
// The corneal ports the instruments enter through and the globe they belong to (seed 001 §3.2,
// seed 002 §7: "the corneal tunnels (both translational and rotational constraint) ... the eye
// globe is rotated in order to reduce the deformation of the tunnel"). Plain data: the ports are
// made once per scene (procedures/scene/tool_ports), the globe state is written every frame by
// systems/tool_eye and read by the metrics.
#include <array>
#include <cstdint>
#include <string>

#include "engine/core/math.hpp"

namespace phaco {

// A tunnel through the cornea, in the globe's rest pose (it turns with the globe).
struct EyePort {
  std::string name;                // "main", "side"
  Vec3 centre_mm = Vec3::Zero();   // middle of the tunnel, inside the corneal stroma
  Vec3 axis = -Vec3::UnitX();      // unit, along the tunnel pointing into the eye
  Vec3 width_dir = Vec3::UnitY();  // unit, ⟂ axis: across the slit (along the limbus)
  double width_mm = 0;             // the slit's width (the blade that cut it)
  double tunnel_length_mm = 0;     // outer to inner opening, along `axis`
  double clock_hour = 0;           // as the surgeon sees the eye (12 = superior, 3 = +x)
};

inline constexpr uint32_t kMaxPortTools = 2;  // one per hand

// One hand's tool after the tool–eye equilibrium (seed 001: "an equilibrium position, to be
// visualized during simulation").
struct ToolPortState {
  int port = -1;                          // index into the scene's ports; −1: not in a port
  Vec3 tip_mm = Vec3::Zero();             // shown tip
  Vec3 shaft = Vec3::UnitZ();             // shown shaft direction (unit, tip → handle)
  Vec3 tip_offset_mm = Vec3::Zero();      // shown tip − hand's tip (warm start)
  Quat shaft_turn = Quat::Identity();     // shown shaft = shaft_turn · hand's shaft (warm start)
  Vec3 port_force_mn = Vec3::Zero();      // what the shaft pushes on the tunnel's borders, mN
  Vec3 port_moment_mn_mm = Vec3::Zero();  // the tunnel's rotational spring on the globe, mN·mm
  double energy_mn_mm = 0;                // this tool's constraint energy (excl. the hand), µJ
};

struct GlobeState {
  Quat rotation = Quat::Identity();                  // about the globe centre, from rest
  std::array<ToolPortState, kMaxPortTools> tools{};  // in scene.tools order
  double energy_mn_mm = 0;  // total energy at the equilibrium (hand springs included)
  int iterations = 0;       // Gauss–Newton steps of the last solve
  int cg_iterations = 0;    // linear CG iterations of the last solve, summed
};

}  // namespace phaco
