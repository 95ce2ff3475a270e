#pragma once
// The peer: the same pinned membrane run in Bullet's btSoftBody (Bullet 2.x soft bodies as shipped
// with Bullet 3.24): same vertices, triangles and springs (one btSoftBody::Link per spring, one
// Face per triangle), rim nodes with mass 0 (fixed), the same lumped masses, rest lengths and
// time step, stepped by btSoftRigidDynamicsWorld::stepSimulation(dt, 0) with no rigid bodies and
// no gravity.
//
// Stiffness mapping. Bullet's link stiffness kLST ∈ [0, 1] is not a spring constant: each solver
// iteration moves a link's two ends kLST of the way to its rest length (position-based dynamics).
// The closest physical reading is XPBD: a spring of stiffness k with inverse masses w = w_i + w_j
// corrected once per step by Δλ = −C/(w + 1/(k·dt²)) moves a fraction k·w·dt²/(1 + k·w·dt²) of the
// way. We set kLST to that fraction for the median spring (Bullet has one material per body here:
// a material per link would cost a pointer chase per link anyway). For the capsule's real
// stiffness at a frame step, k·w·dt² ≫ 1, so kLST → 1 (a rigid link per iteration) and the
// equilibrium no longer depends on k: PBD stiffness depends on iterations and dt, not on E.
#include <cstdint>
#include <memory>

#include "components/particles.hpp"
#include "components/springs.hpp"
#include "components/triangles.hpp"

namespace phaco::perf {

struct BulletMembraneOptions {
  double dt_s = 1.0 / 120;
  int position_iterations = 1;  // btSoftBody::Config::piterations (Bullet's default 1)
  double damping = 0.0;  // btSoftBody::Config::kDP ∈ [0, 1], velocity fraction removed per step
};

class BulletMembrane {
 public:
  // `particles` gives positions, inverse masses (0 = fixed) and velocities are taken as zero.
  BulletMembrane(const Particles& particles, const Triangles& triangles, const Springs& springs,
                 const BulletMembraneOptions& options);
  ~BulletMembrane();
  BulletMembrane(const BulletMembrane&) = delete;
  BulletMembrane& operator=(const BulletMembrane&) = delete;

  // Adds a force (mN) on one node for the next step only (Bullet clears forces after each step).
  void add_force(uint32_t node, float fx, float fy, float fz);
  void step();

  uint32_t node_count() const;
  float link_stiffness() const;  // the kLST chosen (see the mapping above)
  // Node position (mm).
  void position(uint32_t node, float& x, float& y, float& z) const;
  // True when every node position is finite.
  bool finite() const;
  double max_speed_mm_s() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace phaco::perf
