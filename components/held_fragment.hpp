#pragma once
// A lens fragment held at a tool's tip by aspiration (issue 19 item 5): the load the hand feels.
//
// WHO FILLS IT: the drill's aspiration code (nucleus_removal: the probe occludes on a fragment,
// vacuum builds, the fragment is held and drawn to the tip). Put one on the tool entity
// (scene.world.add(tool, HeldFragment{})), declare the access name "tools.held" as written, and
// each frame either set `held = true` with the fields below or `held = false`. Nothing else is
// needed: procedures/scene/haptic_publish copies it into the tool's HapticTool::held, and the
// haptic thread (systems/haptic_model/held_load) renders it.
//
// WHAT THE HAND FEELS: the fragment as a point mass hanging from the tip by a stiff, critically
// damped attachment (the occluded port), in a viscous medium:
//     m·a_f = −k_h·(x_f − P) − c_h·(v_f − v_P) − drag·v_f + weight
// and the tip carries k_h·(x_f − P) + c_h·(v_f − v_P): at rest the weight, at constant speed the
// weight minus the drag, while accelerating the inertia m·a on top — bounded by `hold_limit_mn`
// (the occlusion's grip: beyond it the fragment would break away; whether it does is the
// simulation's decision, the haptic side only caps the load). A 3-DOF device renders no torque,
// so the fragment's rotational inertia about the tip is not felt and not asked for.
//
// Orders of magnitude (so the filler can check its numbers): a quadrant of a 9.4 × 4.5 mm lens is
// ≈ 40 mm³, m ≈ 4e-5 kg; its weight in BSS (ρ 1.07 vs 1.0 g/cm³) ≈ 0.03 mN; Stokes drag
// 6πμR in BSS (μ ≈ 1 mPa·s, R ≈ 2 mm) ≈ 4e-5 mN·s/mm, in a dispersive OVD (μ ~ 1–10 Pa·s at the
// shear rates of a moving tip) 0.04–0.4 mN·s/mm; hold limit = vacuum × port area, 300 mmHg
// (40 kPa) over a 0.6 mm port (0.28 mm²) ≈ 11 mN. Physically the load is small: the fragment is
// felt mostly through the medium's drag and through its contacts, not its weight.
#include <array>
#include <cstdint>

namespace phaco {

struct HeldFragment {
  bool held = false;                 // false: nothing held; every field below is ignored
  uint32_t fragment = 0xffffffffu;   // Fragments id of the held fragment (its cells are not
                                     // published as contacts for this tool: it rides the tip)
  float mass_kg = 0;                 // kg, the fragment's mass
  float drag_mn_s_per_mm = 0;        // mN·s/mm, the medium's drag on it (Stokes 6πμR or fitted)
  std::array<float, 3> weight_mn{};  // mN, world frame: weight less buoyancy (+z toward surgeon)
  float hold_limit_mn = 0;           // mN, largest load the occlusion holds; ≤ 0: no bound
};

}  // namespace phaco
