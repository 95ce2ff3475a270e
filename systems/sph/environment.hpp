#pragma once
// Environment contacts of lens cells (seed 002 §6.1, last paragraph): "treating geometric
// intersections and inelastic collision: the interacting cells are forced to assume a very big
// mass, and the shape-based mesh-less correction scheme adjusts the configuration according to
// the constraints".
//
// A constraint is a sphere that keeps cells inside (capsule bag) or outside (the cornea's
// posterior surface seen from below, an instrument's bulb). A cell found on the wrong side is
// projected back onto the sphere along its radius and loses the velocity component that carried
// it out (inelastic: restitution 0; the tangential part is kept). It is then flagged heavy for
// this step: the caller weights it by kHeavyMassFactor in shape matching (heavy_weight), so the
// fragment's rigid fit moves around the constrained cells instead of pulling them back through.
// Spheres are applied in the order given.
//
// Reads: constraint spheres. Writes: positions, velocities (of constrained cells), heavy flags.
#include <cstdint>
#include <span>

namespace phaco::sph {

struct ConstraintSphere {
  float cx = 0.0f, cy = 0.0f, cz = 0.0f;  // centre, mm
  float radius = 1.0f;                    // mm
  bool keep_inside = true;                // false: keep cells outside
};

// Mass multiplier of a heavy (constrained) cell in shape matching.
inline constexpr float kHeavyMassFactor = 1.0e3f;

inline float heavy_weight(float mass, uint8_t heavy) {
  return heavy ? mass * kHeavyMassFactor : mass;
}

struct EnvironmentParticles {
  std::span<float> x, y, z;     // mm
  std::span<float> vx, vy, vz;  // mm/s
};

// Projects every cell onto the allowed side of every sphere; heavy[i] = 1 where one acted, else 0.
// Returns the number of heavy cells. Parallel per cell; deterministic.
uint32_t constrain_to_spheres(std::span<const ConstraintSphere> spheres,
                              const EnvironmentParticles& particles, std::span<uint8_t> heavy);

}  // namespace phaco::sph
