#pragma once
// The view of one deformable body that every deform system takes: its components by reference,
// and the optional active node set (seed 003 §D): when it is not empty only those particles
// move; the rest are held where they are (sleeping).
#include <cstdint>
#include <span>

#include "components/dynamics.hpp"
#include "components/particles.hpp"
#include "components/springs.hpp"

namespace phaco::deform {

// Environment the membrane lives in (seed 001 §3.4's correction step): the lens surface below
// (two half-ellipsoids) and the posterior cornea above (a sphere). A particle pushed inside the
// lens or past the cornea is put back on the surface and loses its inward velocity.
struct Environment {
  bool has_lens = false;
  double lens_radius_mm = 4.7, lens_anterior_mm = 1.8, lens_posterior_mm = 2.7;
  bool has_cornea = false;
  double cornea_centre_z_mm = 4.8 - 6.5, cornea_radius_mm = 6.5;  // inner (posterior) surface
};

// A force applied from outside (a tool, a test load) to one particle, mN. Constant over a step.
struct PointLoad {
  uint32_t particle = 0;
  float fx = 0.0f, fy = 0.0f, fz = 0.0f;  // mN
};

struct Membrane {
  Particles& particles;
  const Springs& springs;
  const SpringBlocks& blocks;
  Forces& forces;
  const Dynamics& dynamics;
  const Glue* glue = nullptr;
  const Environment* environment = nullptr;
  std::span<const uint32_t> active = {};  // sorted particle indices; empty = every particle
  // Springs with an active end, sorted; used when active is set.
  std::span<const uint32_t> active_springs = {};
  // External point loads (tools, tests); non-finite ones are ignored and counted.
  std::span<const PointLoad> loads = {};
};

}  // namespace phaco::deform
