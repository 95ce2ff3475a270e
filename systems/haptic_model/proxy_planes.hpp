#pragma once
// Internal to systems/haptic_model: the constraint planes the proxy is solved against (step 3 of
// haptic_model.hpp) and the contact kinds that produce them besides the patch and the lens.
#include <array>
#include <cstdint>

#include "components/haptic_model.hpp"
#include "systems/haptic_model/haptic_model.hpp"

namespace phaco::haptic_model::detail {

// Energy of a plane: ½k·pen² while k·pen ≤ cap, then cap·pen − cap²/(2k) (C¹, convex): below the
// cap a spring, past it a constant force — the material yields (the ultrasound cut). cap ≤ 0: no
// bound.
struct Plane {
  Vec3 normal, point;  // outward unit normal, a point of the surface (mm)
  double k;            // mN/mm
  double cap = 0;      // mN
};

// Sphere contacts a tick keeps (the deepest): a 0.45 mm tip pressed into a level-3 lens (cells of
// ≈ 0.1 mm radius) meets up to about a hundred; with 32 the set changed as the tip slid.
inline constexpr uint32_t kMaxSphereContacts = 128;
inline constexpr uint32_t kMaxPortPlanes = 4;  // through the slit, both ways; across, beyond ±w/2
inline constexpr uint32_t kMaxPlanes = kHapticMaxContacts + 1 + kMaxSphereContacts + kMaxPortPlanes;
using Planes = std::array<Plane, kMaxPlanes>;

// Appends the planes of the tool's published spheres (components/haptic_model.hpp) that the tip
// sphere of radius r at the device D presses, seen from `outside` (god-object for spheres: each
// sphere's plane is tangent to it on the side facing that point). Shares ω_j = pen_j / Σ pen (a
// sphere entering or leaving does so with zero weight: the force is continuous as the tip slides
// over the bumps; overlapping spheres act as one surface of stiffness k, not N·k); the cut bound
// is shared the same way, so all spheres together yield at cut_force_mn. rigid_k > 0: every plane
// at that stiffness, no cut (the surface proxy's solve). Returns the new count; `deepest` gets the
// largest penetration at D.
//
// Why a surface proxy: the nucleus is soft next to k_c (k ≈ 100 mN/mm: 50 mN sink the proxy
// 0.5 mm, past the centres of the top cells); normals read from that proxy would turn over
// inside the material and push it further in. So a second, rigid proxy Q is kept on the
// material's surface (solved against the same spheres at rigid stiffness, from its own last
// place), and the soft planes take their normals from Q: they keep facing out however deep the
// tip presses or cuts.
uint32_t add_sphere_planes(const HapticTool& m, const Vec3& outside, const Vec3& device, double r,
                           double rigid_k, Planes& planes, uint32_t count, double& deepest);

// Appends the planes of the tool's port (components/haptic_model.hpp, port_*) for a proxy whose
// shaft runs along `shaft` (unit, tip → handle: the device's): systems/tool_eye's translational
// tunnel spring, ½k_t·(|δ_w| − w/2)₊² + ½k_t·δ_h², with δ the shaft line's offset from the port's
// centre across (w) and through (h) the slit. For a fixed shaft δ is linear in the proxy P,
// δ_e = g_e·(c − P) with g_e = e − (d·e)·d, so each side of each direction is one plane of normal
// ±g_e/|g_e| and stiffness k_t·|g_e|² (the tip radius r cancelled out of the plane's point). The
// springs fade in as the device's tip goes from the port's centre to half a tunnel past it, so
// entering or leaving the port is continuous. Returns the new count (unchanged: no port, no
// shaft, or the tip outside the tunnel).
// `axis_offset`: the device's tip → its shaft's axis (a bent point, turned with the device), which
// the tunnel holds; zero for a straight tool.
uint32_t add_port_planes(const HapticTool& m, const Vec3& device, const Vec3& shaft,
                         const Vec3& axis_offset, double r, Planes& planes, uint32_t count);

// A held fragment's load on the tip this tick (components/held_fragment.hpp): advances the
// fragment (backward Euler, unconditionally stable at any mass) hanging from the proxy P moving at
// V_P, returns k_h·(x_f − P) + c_h·(v_f − V_P) bounded by the hold limit. A fragment newly held
// starts at rest relative to the tip with its weight already hanging (no jolt).
Vec3 held_load(const HeldFragment& fragment, const Vec3& proxy, const Vec3& proxy_velocity,
               const HapticSettings& settings, HeldLoadState& state);

}  // namespace phaco::haptic_model::detail
