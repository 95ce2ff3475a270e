#pragma once
// The corneal ports' mode each input gets in the trainer (issue 20 item 2; docs/trainer.md,
// "Ports"):
//   live inputs (desktop: mouse, keyboard and gamepad; udp:, openhaptics) — "constrain": the
//     tools are held in their ports, the shown pose is the tool–eye equilibrium, so levering on a
//     port turns the globe instead of passing through the cornea; the desktop's shaft also
//     pivots in its port (procedures/scene/port_pivot), since a mouse gives no orientation;
//   scripted, track and replay: — the scenario's mode, else the drill file's ("measure"): their
//     tracks already pivot in the ports (tests/procedures/scene DrillPivot), and a track run is
//     the bit-exact replay of `phaco run`, which measures.
// A scenario that names methods["tools.ports"] keeps its choice; a drill without ports ("off")
// stays off. The session records the scenario it ran, mode included, so replaying a record gives
// the same poses.
#include <array>
#include <optional>
#include <string>

#include "components/eye_ports.hpp"
#include "engine/io/scenario.hpp"
#include "procedures/scene/carried_state.hpp"

namespace phaco {

// desktop, udp:…, openhaptics…; not scripted, track, replay:… or "" (the hand's track).
bool is_live_device(const std::string& spec);

// `s` with methods["tools.ports"] = "constrain" when a hand's device (indexed as Hand) is live,
// `s` does not choose a mode and its drill file has ports. Throws InputError for a bad scenario.
Scenario with_live_ports(const Scenario& s, const std::array<std::string, 2>& devices);

// The port each hand's desktop input pivots in, indexed as Hand: main for the right hand, side for
// the left (the scripted drills' convention); none for a keratome (it cuts its port), a hand
// without a track, or when the ports are off. In a procedure (`carried`), the main port is the
// incision that was cut, as the scene's (procedures/scene/tool_ports).
std::array<std::optional<EyePort>, 2> desktop_ports(const Scenario& running,
                                                    const CarriedState* carried = nullptr);

}  // namespace phaco
