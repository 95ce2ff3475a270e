#include "procedures/scene/tool_ports.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

#include "components/tool.hpp"
#include "engine/core/error.hpp"
#include "engine/io/tool_shape.hpp"
#include "procedures/eye/eye_geometry.hpp"
#include "procedures/scene/method_settings.hpp"
#include "procedures/scene/scene.hpp"

namespace phaco {

namespace {

constexpr double kDegToRad = std::numbers::pi / 180.0;

PortsRecord* record_of(Scene& scene) {
  return scene.bodies.empty() ? nullptr : scene.world.get<PortsRecord>(scene.bodies.front());
}

EyePort make_port(const eye::EyeGeometry& g, const eye::EyeParams& p, std::string name,
                  double clock_hour, double width_mm) {
  // Clock face as the surgeon sees it: 12 = +y, 3 = +x (DESIGN.md §6).
  const double azimuth = (3.0 - clock_hour) * 30.0 * kDegToRad;
  const Vec3 radial(std::cos(azimuth), std::sin(azimuth), 0.0);
  const double rho = g.limbus_radius - p.get("tool_eye.port_inset_mm");
  if (!(rho > 0.0) || rho >= g.cornea_posterior_radius) {
    throw InputError("tool_eye.port_inset_mm: the port radius limbus − inset = " +
                     std::to_string(rho) + " mm is not inside the posterior corneal sphere");
  }
  const double z_front = g.cornea_anterior_centre_z +
                         std::sqrt(g.cornea_anterior_radius * g.cornea_anterior_radius - rho * rho);
  const double z_back =
      g.cornea_posterior_centre_z +
      std::sqrt(g.cornea_posterior_radius * g.cornea_posterior_radius - rho * rho);
  const double angle = p.get("tool_eye.entry_angle_deg") * kDegToRad;
  EyePort port;
  port.name = std::move(name);
  port.centre_mm = rho * radial + Vec3(0.0, 0.0, 0.5 * (z_front + z_back));  // mid-stroma
  port.axis = (-std::cos(angle) * radial - std::sin(angle) * Vec3::UnitZ()).normalized();
  port.width_dir = Vec3(-radial.y(), radial.x(), 0.0);  // along the limbus
  port.width_mm = width_mm;
  port.tunnel_length_mm = p.get("tool_eye.tunnel_length_mm");
  port.clock_hour = clock_hour;
  return port;
}

double rotation_deg(const Quat& q) {
  return tool_eye::rotation_vector(q).norm() / kDegToRad;
}

}  // namespace

std::vector<EyePort> default_ports(const eye::EyeParams& params, double main_clock_hour,
                                   double side_clock_hour) {
  const eye::EyeGeometry g = eye::eye_geometry(params);
  return {make_port(g, params, "main", main_clock_hour, params.get("tools.keratome_width_mm")),
          make_port(g, params, "side", side_clock_hour, params.get("tool_eye.side_port_width_mm"))};
}

tool_eye::EyeShape tool_eye_shape(const eye::EyeParams& params) {
  const eye::EyeGeometry g = eye::eye_geometry(params);
  tool_eye::EyeShape e;
  e.globe_centre_mm = Vec3(0.0, 0.0, g.globe_centre_z);
  e.cornea_centre_mm = Vec3(0.0, 0.0, g.cornea_posterior_centre_z);
  e.cornea_posterior_radius_mm = g.cornea_posterior_radius;
  e.lens_centre_mm = Vec3::Zero();  // the frame's origin (DESIGN.md §6)
  e.lens_equator_radius_mm = g.lens_a;
  e.lens_anterior_mm = g.lens_c_anterior;
  e.lens_posterior_mm = g.lens_c_posterior;
  return e;
}

tool_eye::Stiffness tool_eye_stiffness(const eye::EyeParams& p) {
  tool_eye::Stiffness k;
  k.hand_mn_mm = p.get("tool_eye.hand_stiffness_mn_mm");
  k.hand_rot_mn_mm_rad = p.get("tool_eye.hand_rotational_stiffness_mn_mm_per_rad");
  k.tunnel_mn_mm = p.get("tool_eye.tunnel_stiffness_mn_mm");
  k.tunnel_rot_mn_mm_rad = p.get("tool_eye.tunnel_rotational_stiffness_mn_mm_per_rad");
  k.tunnel_free_angle_rad = p.get("tool_eye.tunnel_free_angle_deg") * kDegToRad;
  k.cornea_mn_mm = p.get("tool_eye.cornea_stiffness_mn_mm");
  k.lens_mn_mm = p.get("tool_eye.lens_stiffness_mn_mm");
  k.globe_rot_mn_mm_rad = p.get("tool_eye.globe_rotational_stiffness_mn_mm_per_rad");
  return k;
}

bool is_ports_method(const std::string& key) {
  return key == "tools.ports";
}

std::string ports_mode(const Scene& scene) {
  // The drill file's "ports" (validated by engine/io/drill_file) when the scenario does not say.
  return method_value(scene.scenario, "tools.ports", scene.drill.ports);
}

std::optional<SystemDesc> tool_ports_system(Scene& scene) {
  const std::string mode = ports_mode(scene);
  if (mode == "off" || scene.bodies.empty()) return std::nullopt;
  PortsRecord r;
  // Where the ports are is the drill's (guidance.incision_site and side_port, data/drills).
  const Guidance& g = scene.drill.guidance;
  if (!g.incision_site || !g.side_port) {
    throw InputError(scene.scenario.source + ": tools.ports " + mode + ": the drill file " +
                     scene.drill.source +
                     " names no guidance.incision_site and side_port for the ports");
  }
  try {
    r.ports = default_ports(scene.params, g.incision_site->clock_hour, g.side_port->clock_hour);
  } catch (const InputError& e) {
    throw InputError(scene.scenario.source + ": eye: " + e.what());
  }
  // In a procedure the main port is the incision the trainee cut (procedures/procedure/carry).
  if (scene.carried.main_port) r.ports.front() = *scene.carried.main_port;
  r.eye = tool_eye_shape(scene.params);
  r.stiffness = tool_eye_stiffness(scene.params);
  r.constrain = mode == "constrain";
  // The port_stress event fires where the drill's target for the port force ends.
  const auto target = scene.drill.targets.find("ports.max_force_mN");
  r.stress_force_mn = target != scene.drill.targets.end() && target->second.max
                          ? *target->second.max
                          : std::numeric_limits<double>::infinity();
  scene.world.name_component<PortsRecord>("tools.ports", AccessKind::Global);
  scene.world.add(scene.bodies.front(), std::move(r));

  std::vector<std::string> writes = {"tools.ports"};
  if (mode == "constrain") writes.push_back("tools.pose");
  return SystemDesc{
      .name = "tool_ports",
      .phase = Phase::Input,
      .reads = {"tools.pose"},
      .writes = std::move(writes),
      .after = {"move_tools"},
      .run = [&scene](const FrameContext&) {
        PortsRecord* rec = record_of(scene);
        if (!rec) return;
        GlobeState& globe = rec->globe;
        std::array<tool_eye::HandPose, kMaxPortTools> hands{};
        const size_t n = std::min<size_t>(kMaxPortTools, scene.tools.size());
        for (size_t i = 0; i < n; ++i) {
          const ToolState& pose = scene.world.at<ToolState>(scene.tools[i]);
          tool_eye::HandPose& h = hands[i];
          const ToolKind kind = scene.world.at<Tool>(scene.tools[i]).kind;
          // The tunnel holds the drawn shaft: its axis, beside the tip by a bent point.
          const ShaftAxis axis = shaft_axis(pose, kind);
          h.tip_mm = pose.pos;
          h.shaft = axis.direction;
          h.axis_offset_mm = axis.point - pose.pos;
          // The phaco probe's and the chopper's work is inside the nucleus (its trenches and
          // cracks): the lens is no boundary for them. With the spring, the chopper down in the
          // trench (2.8 mm inside the uncut lens's surface) pressed the side port 147 mN and
          // turned the globe 9°, which pushed the main port onto the probe's shaft as well.
          h.lens_spring = kind != ToolKind::PhacoProbe && kind != ToolKind::Chopper;
          // The keratome cuts its tunnel (cornea_cutting), it does not pass through one: the
          // ports model finished incisions, and a blade pressed through the slit "across" would
          // be read as a tunnel pushed on (82 mN for the incision expert) when it is the cut.
          h.port = kind == ToolKind::Keratome
                       ? -1
                       : tool_eye::engaged_port(rec->ports, globe.rotation,
                                                rec->eye.globe_centre_mm, h.tip_mm, h.shaft,
                                                globe.tools[i].port, h.axis_offset_mm);
        }
        tool_eye::solve(rec->ports, rec->eye, rec->stiffness,
                        std::span<const tool_eye::HandPose>(hands.data(), n), globe);
        ++rec->solves;
        rec->cg_iterations += static_cast<uint64_t>(globe.cg_iterations);
        rec->max_cg_iterations = std::max(rec->max_cg_iterations, globe.cg_iterations);
        rec->max_rotation_deg = std::max(rec->max_rotation_deg, rotation_deg(globe.rotation));
        for (size_t i = 0; i < kMaxPortTools; ++i) {
          const double f = i < n ? globe.tools[i].port_force_mn.norm() : 0.0;
          rec->force_mn[i] = f;
          rec->max_force_mn = std::max(rec->max_force_mn, f);
          const bool stressed = f > rec->stress_force_mn;
          rec->stress_began[i] = stressed && !rec->stressed[i];
          rec->stressed[i] = stressed;
        }
        if (!rec->constrain) return;
        for (size_t i = 0; i < n; ++i) {
          if (globe.tools[i].port < 0) continue;  // a free tool is where the hand has it
          ToolState& pose = scene.world.at<ToolState>(scene.tools[i]);
          pose.pos = globe.tools[i].tip_mm;
          pose.quat = (globe.tools[i].shaft_turn * pose.quat.normalized()).normalized();
        }
      }};
}

const PortsRecord* ports_record(const Scene& scene) {
  return scene.bodies.empty() ? nullptr : scene.world.get<PortsRecord>(scene.bodies.front());
}

bool port_stress_began(const Scene& scene, size_t index, double& force_mn) {
  const PortsRecord* r = ports_record(scene);
  if (!r || index >= kMaxPortTools || !r->stress_began[index]) return false;
  force_mn = r->force_mn[index];
  return true;
}

void ports_metrics(const Scene& scene, nlohmann::json& metrics) {
  const PortsRecord* r = ports_record(scene);
  if (!r) return;
  metrics["globe.max_rotation_deg"] = r->max_rotation_deg;
  metrics["ports.max_force_mN"] = r->max_force_mn;
}

}  // namespace phaco
