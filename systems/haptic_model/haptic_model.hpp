#pragma once
// The haptic thread's local force model (issue 6 item 3; seed 003 §III.C–E): from the newest
// HapticTool (components/haptic_model.hpp) and the device's position, one 1 kHz tick computes the
// force to send to the device, without waiting for the simulation. docs/haptic_model.md.
//
//   device D ──k_c, b_c (virtual coupling)── proxy P ──k_p── patch triangles ── springs ── anchors
//                                                   ├─k_f── lens (seed 003 §E.5: F = −k_f·d)
//                                                   └─k_t── port: the shaft's line to the tunnel
//   grasp: the grasped node IS the proxy; the user feels its springs (the flap's spring)
//
// Per tick, per model being integrated (two during a crossfade):
//   1. contacts of the tip sphere (radius r) with the patch triangles, seen from the device
//      position, each triangle's side remembered (god-object, Zilles & Salisbury 1995: the proxy
//      never passes through a triangle). Every pressed triangle is a constraint weighted by its
//      share of the total penetration, so the contact is one surface, not counted once per facet,
//      and its force is continuous as the tip slides from facet to facet;
//   2. local nodes: one backward-Euler step (Baraff & Witkin 1998) of the free and grasped nodes
//      under their springs (seed 003 §E.1, f = −k·dx), damping −(k_d + k_v)·v (§E.2–3), the
//      contact pushing the touched triangle (series stiffness k_c·k_p/(k_c + k_p), barycentric on
//      its corners) and the grasp holding the grasped node to the device by k_c; solved by a
//      matrix-free Jacobi-preconditioned CG on fixed arrays, warm-started, iteration-capped.
//      At the capsule's m ≈ 1e-10 kg, k ≈ 40 mN/mm the explicit step has ω·dt ≈ 600 at 1 ms:
//      the implicit step is the quasi-static limit with the seed's viscosity, and stays bounded;
//   3. proxy: P = argmin ½k_c|P − D|² + Σ ½ω_j·k_p·pen_j(P)² + ½k_f·d_lens(P)² over the
//      contact planes (weights ω_j) and the lens tangent plane (Newton on its quadratic pieces,
//      each an exact 3×3 solve, with backtracking on the energy);
//   4. force F = −k_c·(D − P) − b_c·(V_D − V_P), clamped to the device's maximum; a grasp's at
//      most the model's grasp_limit_mn (the held flap tears there: systems/tear's resistance).
// Lens material (issue 19 item 5, sphere_contacts.cpp): the published spheres enter step 3 as
// planes tangent to each sphere facing the proxy, shared like the patch's facets, each with its
// stiffness and, under ultrasound, a force bound (a plane's energy turns linear past it: the tip
// cuts through). A held fragment (held_load.cpp) adds its load to step 4's force.
// Port (issue 20 item 2, port_planes.cpp): the tunnel the tool is in enters step 3 as planes on
// the proxy's shaft line, the shaft the device's own (its orientation this tick), so a hand that
// levers against the port feels the tunnel's spring at once and one that pivots about its centre
// feels nothing; while grasping, the same planes give a proxy of their own whose coupling force is
// added.
// A new model is crossfaded in (both models ticked, forces mixed linearly over blend_ms, the
// output's change per tick beyond the models' own bounded by blend_max_step_mn until it has caught
// up), so the force is continuous; a stalled simulation leaves the last model running.
//
// Access: reads the HapticTool given, the device sample and the settings; writes the
// HapticToolState only (the haptic thread's own). No allocation, lock, system call or throw in
// adopt_model or haptic_tick.
#include <array>
#include <cstdint>

#include "components/haptic_model.hpp"
#include "engine/core/math.hpp"

namespace phaco::haptic_model {

enum class NodeIntegrator : uint8_t {
  ImplicitEuler,   // the default: bounded at any stiffness and mass
  SymplecticEuler  // explicit, for the test and the study that show why not
};

struct HapticSettings {
  double coupling_stiffness_mn_per_mm = 1000.0;  // k_c; a Phantom Omni renders ≈ 1–2 N/mm
  double coupling_damping_mn_s_per_mm = 0.0;  // b_c; lowers the passive k (Colgate: b > KT/2 + B)
  double max_force_mn = 3300.0;               // the device's limit (Omni 3.3 N)
  double blend_ms = 4.0;                      // crossfade to a new model; 0 = switch at once
  // While a new model comes in, the output's change per tick beyond the models' own, at most
  // (0 = no bound).
  double blend_max_step_mn = 1.0;
  double dt_s = 0.001;               // tick
  int solver_iterations = 24;        // CG cap per tick (warm-started)
  double solver_tolerance = 1.0e-6;  // relative CG residual to stop earlier
  double contact_margin_mm =
      0.05;  // a triangle's side is re-read when the proxy is this far past r
  double contact_max_depth_mm = 2.0;  // deeper than this behind a triangle: not that triangle's
  double rigid_ratio = 1000.0;        // patch_stiffness ≤ 0 means rigid: k_p = rigid_ratio·k_c
  // Untouched nodes whose net forces are all below this (mN) and velocities below 1e-6 mm/s
  // sleep through the tick (no solve): an idle tool costs a spring pass only.
  double sleep_force_mn = 1e-4;
  NodeIntegrator integrator = NodeIntegrator::ImplicitEuler;
  // A held fragment hangs from the tip by this spring, critically damped (held_load.cpp): stiff
  // against the fragment's weight (its sag W/k_h is microns), soft against k_c.
  double held_stiffness_mn_per_mm = 20.0;
};

// Which terms the force came from (bits of HapticForce::active).
enum HapticTerm : uint8_t {
  kTermContact = 1,
  kTermGrasp = 2,
  kTermLens = 4,
  kTermBlend = 8,
  kTermSpheres = 16,  // lens material (spheres) pressed
  kTermCut = 32,      // ... and its reaction at the ultrasound cut bound
  kTermHeld = 64,     // a held fragment's load
  kTermPort = 128     // the port's tunnel pressed by the shaft
};

struct HapticForce {
  Vec3 force_mn = Vec3::Zero();  // to the device, clamped
  Vec3 proxy_mm = Vec3::Zero();  // of the newest model
  double penetration_mm = 0;     // deepest patch contact of the proxy's tip sphere (newest model)
  double lens_depth_mm = 0;      // d of seed 003 §E.5 at the proxy (newest model)
  double sphere_depth_mm = 0;    // deepest sphere penetration of the device's tip (newest model)
  Vec3 held_load_mn = Vec3::Zero();  // a held fragment's load in the force (newest model)
  double blend_weight = 1;           // weight of the newest model, 0..1
  uint8_t active = 0;                // HapticTerm bits
  bool clamped = false;              // the force hit max_force_mn
  bool input_rejected = false;       // NaN/inf device sample: zero force, state untouched
  int solver_iterations = 0;         // CG iterations of the newest model this tick
};

// Lens penetration (seed 003 §E.5) of a sphere of radius r at p into the two half-ellipsoids of
// `tool` (lens_* fields): depth = r − signed distance to the surface (> 0 when touching), the
// outward normal and nearest surface point. Distance exact to ~1e-9 mm: each half's meridian arc
// is scanned at 32 angles and the best refined by Newton on the arc parameter (the scan bounds the
// global minimum; the refinement makes it exact).
struct LensContact {
  double depth_mm = -1;  // r − signed distance; ≤ 0: not touching
  double signed_distance_mm = 0;
  Vec3 normal = Vec3::UnitZ();  // outward at the nearest point
  Vec3 nearest_mm = Vec3::Zero();
};
LensContact lens_penetration(const HapticTool& tool, const Vec3& p, double radius_mm);

// Patch triangles the tip sphere may press at once (a vertex of a grid has 6 or 8 around it).
inline constexpr uint32_t kHapticMaxContacts = 16;

struct HapticContact {
  uint32_t triangle = 0;
  std::array<double, 3> w{};    // barycentric weights of the contact point on the triangle
  Vec3 normal = Vec3::UnitZ();  // from the surface toward the tool
  Vec3 point = Vec3::Zero();    // surface point, mm
  double penetration_mm = 0;    // r − distance along normal, > 0 when pressed
  double weight = 0;            // its share of the contact (Σ ≤ 1; = 1 over faces)
};

// A held fragment's motion (held_load.cpp), per slot.
struct HeldLoadState {
  bool live = false;                        // following a held fragment
  Vec3 x = Vec3::Zero(), v = Vec3::Zero();  // fragment's centre, mm, mm/s
  Vec3 load = Vec3::Zero();                 // on the tip last tick, mN
};

// One model being integrated: its own copy of the model (so the triple buffer's slot can be
// handed back at once) and the nodes' state.
struct HapticSlot {
  HapticTool model;
  bool live = false;
  std::array<double, kHapticMaxNodes> x{}, y{}, z{}, vx{}, vy{}, vz{};  // mm, mm/s
  std::array<double, 3 * kHapticMaxNodes> warm_dv{};  // the last Δv, CG's first guess
  std::array<int8_t, kHapticMaxTriangles> side{};     // +1/−1: the tool's side of each triangle
  Vec3 proxy = Vec3::Zero(), proxy_velocity = Vec3::Zero();  // mm, mm/s
  Vec3 surface_proxy = Vec3::Zero();  // on the lens material's surface (proxy_planes.hpp), mm
  Vec3 force = Vec3::Zero();          // this model's force last tick, mN
  double penetration_mm = 0, lens_depth_mm = 0, sphere_depth_mm = 0;
  HeldLoadState held;
  uint8_t active = 0;
  int iterations = 0;
};

// Scratch of one tick (shared by the slots; overwritten every tick).
struct HapticScratch {
  std::array<double, kHapticMaxSprings> sa{}, sb{}, sdx{}, sdy{}, sdz{};  // blocks a·d̂d̂ᵀ + b·I
  std::array<double, 3 * kHapticMaxNodes> rhs{}, r{}, zr{}, p{}, q{}, dv{}, diag{};
  std::array<double, 3 * kHapticMaxNodes> m3{}, u3{};  // per unknown: m + dt·c, and 1 (0: fixed)
  std::array<uint8_t, kHapticMaxNodes> unknown{};      // 1: free or grasped
  std::array<double, kHapticMaxTriangles> tnx{}, tny{}, tnz{}, td{};    // unit normals, n·corner0
  std::array<double, kHapticMaxTriangles> tcx{}, tcy{}, tcz{}, trad{};  // bounding sphere, mm
  std::array<uint8_t, kHapticMaxTriangles> tvalid{};                    // 0: degenerate
};

// What the haptic thread keeps per tool between ticks. ≈ 260 KiB: allocate it once on the heap
// (std::make_unique) at start-up; nothing in it allocates afterwards.
struct HapticToolState {
  std::array<HapticSlot, 2> slot;
  uint8_t newest = 0;          // slot of the newest model
  bool blending = false;       // the other slot still contributes
  bool slewing = false;        // since the last adopt, until the output has caught up
  double blend_weight = 1;     // of the newest slot
  Vec3 offset = Vec3::Zero();  // a model replaced mid-blend: its share, decayed over blend_ms
  double offset_weight = 0;    // 1 → 0
  Vec3 last_device = Vec3::Zero();
  bool has_device = false;
  Vec3 last_force = Vec3::Zero();  // sent last tick, mN
  HapticScratch scratch;
  // Counters.
  uint64_t ticks = 0, models_adopted = 0, inputs_rejected = 0, clamped_ticks = 0, slot_resets = 0;

  const HapticTool& newest_model() const { return slot[newest].model; }
};

// A new model arrived (copied into the state): the newest slot starts from its published nodes,
// the proxy carried over from the current one (or the model's tip), and the crossfade begins.
void adopt_model(const HapticTool& model, HapticToolState& state, const HapticSettings& settings);

// One tick; `device_shaft_dir` is the device's shaft (tip → handle, any length; zero: a device
// without orientation, which feels no port). `model` is the newest model as last given to
// adopt_model (the state integrates its own copy; if `model` visibly differs from it — presence,
// node, triangle or sphere count, grasped node, held fragment — it is adopted first). Device
// position mm, velocity mm/s (a NaN/inf sample: zero force, state kept).
HapticForce haptic_tick(const HapticTool& model, const Vec3& device_pos_mm,
                        const Vec3& device_vel_mm_s, const Vec3& device_shaft_dir,
                        const HapticSettings& settings, HapticToolState& state);
// The same for a tool whose shaft's axis runs beside its tip (a bent point): the port holds the
// line through device_pos_mm + device_axis_offset_mm (the tool's bend turned with the device,
// engine/io/tool_shape) along the shaft, the drawn shaft, as the scene's ports do.
HapticForce haptic_tick(const HapticTool& model, const Vec3& device_pos_mm,
                        const Vec3& device_vel_mm_s, const Vec3& device_shaft_dir,
                        const Vec3& device_axis_offset_mm, const HapticSettings& settings,
                        HapticToolState& state);
// The same without the device's orientation (no port term).
HapticForce haptic_tick(const HapticTool& model, const Vec3& device_pos_mm,
                        const Vec3& device_vel_mm_s, const HapticSettings& settings,
                        HapticToolState& state);

}  // namespace phaco::haptic_model
