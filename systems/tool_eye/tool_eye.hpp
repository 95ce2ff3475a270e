#pragma once
// Tool–eye interaction (seed 001 §3.2, seed 002 §7): instruments in the corneal ports, the ports'
// push turning the globe against the extraocular muscles. "A simple conjugate gradient descent is
// employed to minimize the total deformation energy of the following constraints: the corneal
// tunnels (both translational and rotational constraint), the internal cornea surface, and the
// external crystalline surface (unidirectional radial interaction) ... the eye globe is rotated in
// order to reduce the deformation of the tunnel ... All constraints are simply modeled as linear
// springs."
//
// Unknowns (15): per tool slot i (≤ 2) the shown tip offset u_i from the hand's tip and the shown
// shaft's turn φ_i from the hand's shaft (a rotation about the tip); the globe's rotation θ about
// its centre. The ports, the cornea and the lens turn with the globe. Energy (mN·mm = µJ):
//
//   E = Σ_i ½k_h|u_i|² + ½k_hr|φ_i|²                      the hand/device pulls the tool
//     + Σ_i ½k_t (|δ_w| − w/2)₊² + ½k_t δ_h²              tunnel, translational (a slit: free
//                                                         across its width w, tight through it)
//     + Σ_i ½k_tr (β − β_free)₊²                          tunnel, rotational (shaft vs axis)
//     + Σ_i ½k_c (|p − c_cornea| − R_post)₊²               tip inside the inner cornea surface
//     + Σ_i ½k_l (depth in the lens)₊²                     tip outside the lens's half-ellipsoids,
//                                                         depth measured radially from its centre
//     + ½k_g|θ|²                                          the muscles (isotropic)
//
// δ is the shaft's axis's offset from the (rotated) port centre at its closest point (the axis
// runs beside the tip by a bent point: HandPose::axis_offset_mm), split along
// the slit's width direction w and its through direction h = axis × w. Only a tool engaged in a
// port (engaged_port) has tunnel, cornea and lens springs: a tool outside every port is free.
//
// Solver: Gauss–Newton over the piecewise-quadratic energy — each step linearises the residuals
// at the current state (exact rotations for geometry, left-multiplied small rotations for the
// Jacobians, so ½k|θ|²'s gradient is exactly k·θ) and solves the 15×15 SPD system with a
// Jacobi-preconditioned linear conjugate gradient on fixed-size Eigen matrices, then backtracks
// on the energy. Why not nonlinear CG on E: the springs span four decades of stiffness (hand
// rotation 1e5 vs muscles' lever-arm 6e3 vs tunnel 2e2), which makes nonlinear CG crawl, while a
// linear CG on a fixed active set converges in ≤ 15 steps in exact arithmetic, and the few
// Gauss–Newton steps handle the one-sided springs switching. Why not Eigen's ConjugateGradient:
// it works on dynamic vectors (allocates). Warm-started from the last frame's state; fixed caps
// (SolverOptions); no allocation, no throw; a non-finite result resets to the hand poses.
//
// Reads: the ports, the hands' poses. Writes: GlobeState (its own component).
#include <Eigen/Dense>
#include <span>

#include "components/eye_ports.hpp"

namespace phaco::tool_eye {

inline constexpr int kUnknowns = 6 * static_cast<int>(kMaxPortTools) + 3;
using Vector = Eigen::Matrix<double, kUnknowns, 1>;
using Matrix = Eigen::Matrix<double, kUnknowns, kUnknowns>;

// Spring constants: translational mN/mm, rotational mN·mm/rad.
struct Stiffness {
  double hand_mn_mm = 0;
  double hand_rot_mn_mm_rad = 0;
  double tunnel_mn_mm = 0;
  double tunnel_rot_mn_mm_rad = 0;
  double tunnel_free_angle_rad = 0;
  double cornea_mn_mm = 0;
  double lens_mn_mm = 0;
  double globe_rot_mn_mm_rad = 0;
};

// The eye at rest (DESIGN.md §6 frame).
struct EyeShape {
  Vec3 globe_centre_mm = Vec3::Zero();
  Vec3 cornea_centre_mm = Vec3::Zero();  // centre of the posterior corneal sphere
  double cornea_posterior_radius_mm = 0;
  Vec3 lens_centre_mm = Vec3::Zero();  // centre of the lens's equatorial plane
  double lens_equator_radius_mm = 0, lens_anterior_mm = 0, lens_posterior_mm = 0;
};

// One hand's pose this frame (from the track or the device) and the port it is in.
struct HandPose {
  Vec3 tip_mm = Vec3::Zero();
  Vec3 shaft = Vec3::UnitZ();  // tip → handle
  int port = -1;               // engaged_port's answer; −1: free
  bool lens_spring = true;     // false for a tool whose work is inside the lens (probe, chopper)
  // Tip → the shaft's axis at the hand's pose, mm, ⟂ shaft (a bent point: the cystotome's,
  // the chopper's; engine/io/tool_shape). The tunnel holds that line, the drawn shaft, and it
  // turns with the tool about the tip. Zero for a straight tool.
  Vec3 axis_offset_mm = Vec3::Zero();
};

struct SolverOptions {
  int max_steps = 8;           // Gauss–Newton steps (linear rate ≈ 0.1 per step: the GN Hessian
                               // leaves out the springs' curvature terms k·r·∇²r)
  int max_cg = 2 * kUnknowns;  // linear CG iterations per step
  // Stop when |∇E|∞ is below this (mN on a tip, mN·mm on a rotation): a thousandth of a mN is far
  // below what a port force or a globe rotation shows. Tests ask for 1e-10 to check fixed points.
  double gradient_tol = 1e-3;
};

// Which port the tool is in: the tip past the port's outer opening, the shaft heading out of the
// eye, and the shaft's axis (through tip + axis_offset, HandPose) within a port width of its
// centre (nearest wins). Once in a port the tool stays in it until the tip is back out of the
// tunnel (pushing hard does not free it). −1 for a tool outside every port, or a non-finite or
// zero shaft.
int engaged_port(std::span<const EyePort> ports, const Quat& globe_rotation,
                 const Vec3& globe_centre, const Vec3& tip_mm, const Vec3& shaft, int current,
                 const Vec3& axis_offset_mm = Vec3::Zero());

// Minimises E from `state` (the last frame's: warm start) and writes the equilibrium into it.
// Hands beyond kMaxPortTools are ignored. Never throws, never allocates.
void solve(std::span<const EyePort> ports, const EyeShape& eye, const Stiffness& k,
           std::span<const HandPose> hands, GlobeState& state, const SolverOptions& options = {});

// The quadratic (Gauss–Newton) model of E at `state`: E(x + Δ) ≈ energy + gᵀΔ + ½ΔᵀHΔ, with Δ the
// unknowns' increments in the order u_0, φ_0, u_1, φ_1, θ. For tests and the docs' checks.
struct Quadratic {
  Matrix hessian = Matrix::Zero();
  Vector gradient = Vector::Zero();
  double energy = 0;
};
Quadratic linearise(std::span<const EyePort> ports, const EyeShape& eye, const Stiffness& k,
                    std::span<const HandPose> hands, const GlobeState& state);

// Jacobi-preconditioned CG on H·x = b from the given x; returns the iterations used.
int conjugate_gradient(const Matrix& h, const Vector& b, Vector& x, int max_iterations,
                       double tolerance);

// Rotation vector (axis·angle, rad) of a unit quaternion, angle in [0, π].
Vec3 rotation_vector(const Quat& q);

}  // namespace phaco::tool_eye
