#include "procedures/trainer/live_ports.hpp"

#include "procedures/scene/method_settings.hpp"
#include "procedures/scene/scene.hpp"
#include "procedures/scene/scene_inputs.hpp"
#include "procedures/scene/tool_ports.hpp"

namespace phaco {

bool is_live_device(const std::string& spec) {
  return spec == "desktop" || spec.starts_with("udp:") || spec.starts_with("openhaptics");
}

Scenario with_live_ports(const Scenario& s, const std::array<std::string, 2>& devices) {
  if (s.methods.count("tools.ports")) return s;
  bool live = false;
  for (Hand h : {Hand::Left, Hand::Right})
    live |= s.find_hand(h) && is_live_device(devices[static_cast<size_t>(h)]);
  if (!live || load_drill_for(s).ports == "off") return s;
  Scenario out = s;
  out.methods["tools.ports"] = "constrain";
  return out;
}

std::array<std::optional<EyePort>, 2> desktop_ports(const Scenario& running,
                                                    const CarriedState* carried) {
  std::array<std::optional<EyePort>, 2> out;
  const SceneInputs in = check_scene_inputs(running);
  const Guidance& g = in.drill.guidance;
  if (method_value(running, "tools.ports", in.drill.ports) == "off" || !g.incision_site ||
      !g.side_port)
    return out;
  auto ports = default_ports(in.params, g.incision_site->clock_hour, g.side_port->clock_hour);
  if (carried && carried->main_port) ports.front() = *carried->main_port;
  for (Hand h : {Hand::Left, Hand::Right}) {
    const HandTrack* t = running.find_hand(h);
    if (!t || t->tool == ToolKind::Keratome) continue;
    out[static_cast<size_t>(h)] = ports[h == Hand::Right ? 0 : 1];
  }
  return out;
}

}  // namespace phaco
