#pragma once
// The scene's corneal ports and the tool–eye equilibrium each frame (seed 001 §3.2, seed 002 §7;
// systems/tool_eye does the minimisation, docs/tool_eye_interaction.md).
//
// Mode, scenario `methods["tools.ports"]`, else the drill file's "ports" (every shipped drill:
// "measure"; a drill file without the field: "off"):
//   "off"       no ports, no system: scenes and their state hashes as before;
//   "measure"   each frame, after move_tools, find which port each tool is in and solve the
//               equilibrium; record the globe's rotation and the port forces; ToolState untouched;
//   "constrain" the same, and write the shown (equilibrium) pose into ToolState, so the rest of
//               the frame works with the tool where the ports let it be.
//
// Reads: tools.pose. Writes: tools.ports (PortsRecord, on the scene's first body) and, in
// "constrain", tools.pose. Per frame: no allocation.
#include <array>
#include <cstdint>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "components/eye_ports.hpp"
#include "engine/schedule/system.hpp"
#include "procedures/eye/eye_params.hpp"
#include "systems/tool_eye/tool_eye.hpp"

namespace phaco {

struct Scene;

// Two ports at the limbus ("main", keratome width; "side", tool_eye.side_port_width_mm), centred
// tool_eye.port_inset_mm inside the limbus at mid-thickness of the cornea, tunnels
// tool_eye.tunnel_length_mm long running inward and down at tool_eye.entry_angle_deg below the
// iris plane. Throws InputError naming the parameters if the port falls outside the cornea.
std::vector<EyePort> default_ports(const eye::EyeParams& params, double main_clock_hour,
                                   double side_clock_hour);

// The solver's view of the eye and its springs, from the eye parameters (tool_eye.*, cornea.*,
// lens.*, globe.*).
tool_eye::EyeShape tool_eye_shape(const eye::EyeParams& params);
tool_eye::Stiffness tool_eye_stiffness(const eye::EyeParams& params);

// The ports' record: what the metrics read.
struct PortsRecord {
  std::vector<EyePort> ports;
  tool_eye::EyeShape eye;
  tool_eye::Stiffness stiffness;
  bool constrain = false;
  GlobeState globe;
  double stress_force_mn = 0;  // the drill's ports.max_force_mN target (∞: none)
  double max_rotation_deg = 0, max_force_mn = 0;
  std::array<double, kMaxPortTools> force_mn{};    // |port force| this frame, per tool
  std::array<bool, kMaxPortTools> stressed{};      // above the threshold this frame
  std::array<bool, kMaxPortTools> stress_began{};  // crossed it upward this frame
  uint64_t solves = 0, cg_iterations = 0;
  int max_cg_iterations = 0;
};

bool is_ports_method(const std::string& key);  // "tools.ports"

// The scenario's methods["tools.ports"] if given, else the drill file's "ports": "off",
// "measure" or "constrain"; InputError naming the scenario and key otherwise.
std::string ports_mode(const Scene& scene);

// Adds the ports and their record and returns the Input-phase system (after move_tools); nullopt
// when the mode is "off".
std::optional<SystemDesc> tool_ports_system(Scene& scene);

// Null when the ports are off.
const PortsRecord* ports_record(const Scene& scene);

// Metrics hooks (procedures/scene/drill_metrics): whether tool `index` (scene.tools order) began
// pressing its port beyond the threshold this frame, and with what force;
bool port_stress_began(const Scene& scene, size_t index, double& force_mn);
// and, at the end of the run, `globe.max_rotation_deg` and `ports.max_force_mN` (their targets are
// the drill file's). Nothing when off.
void ports_metrics(const Scene& scene, nlohmann::json& metrics);

}  // namespace phaco
