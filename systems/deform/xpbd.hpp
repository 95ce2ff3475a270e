#pragma once
// XPBD: springs as compliant distance constraints (Macklin, Müller, Chentanez 2016, "XPBD:
// position-based simulation of compliant constrained dynamics"), a modern alternative the seeds
// did not have. Stable at any step: the stiffness enters as compliance α = 1/k, never as k·dt².
//
//   predict   v ← (v + dt·f_ext/m̃) / (1 + dt·c),   x̃ = x + dt·v        (f_ext: gravity, loads)
//   iterate   for each spring, C = l − l0 (Hooke) or C = √(2/3)·(l − l0)·√|l − l0| (quadratic:
//             ½C²/α is then k·|l − l0|³/3, the quadratic law's energy), α̃ = α/dt²:
//                 Δλ = (−C − α̃·λ) / (Σ w·|∇C|² + α̃),   x_i += w_i·∇_i C·Δλ,   λ += Δλ
//             then each glue spring as three zero-length constraints with α = 1/k_glue
//   finish    v = (x − x_start)/dt
//
// The solve works on the step's displacement d = x − x_start, kept in its own arrays, not on x:
// v = d/dt then carries no cancellation. Updating x in place and differencing it, the float
// rounding of x (ulp 2.4e-7 mm at 2 mm) divided by a microsecond step is a velocity noise of
// 0.1 mm/s per step, which kept a damped patch jittering at ~3 mm/s (measured).
//
// λ starts at zero every step. The iterations are Gauss-Seidel in a fixed order: with the whole
// body, even SpringBlocks in parallel then odd ones (two blocks of one parity share no particle),
// springs in index order inside a block; with an active set, the active springs in list order.
// Sleeping, anchored and scripted particles have w = 0. With few iterations a stiff body comes
// out softer than it is (λ not converged); the error is measured in tests and perf/.
//
// Reads: springs, blocks, dynamics, glue, loads. Writes: particles (x, v of free particles in
// play), forces (as scratch for the external ones).
#include <cstdint>
#include <vector>

#include "systems/deform/membrane.hpp"
#include "systems/deform/particle_set.hpp"

namespace phaco::deform {

struct XpbdScratch {
  uint16_t iterations = 4;
  std::vector<float> lambda;       // per spring, mN·s²
  std::vector<float> glue_lambda;  // 3 per particle
  std::vector<float> dx, dy, dz;   // the step's displacement, mm
  std::vector<uint8_t> in_play;    // restricted set mask; all zero between steps
};

Motion xpbd_step(Membrane& m, double dt_s, XpbdScratch& scratch);

}  // namespace phaco::deform
