#pragma once
// Bodies for the deform tests: one spring-mass, a pinned square patch, the anterior capsule with
// its published material (E = 2 MPa, h = 0.013 mm, ρ = 1000 kg/m³), and state helpers.
#include <cmath>
#include <cstring>
#include <vector>

#include "procedures/eye/eye_mesh.hpp"
#include "systems/deform/deform.hpp"
#include "systems/springs/springs.hpp"
#include "tests/support/particle_checks.hpp"

namespace phaco::deform_test {

struct Body {
  Particles particles;
  Triangles triangles;
  Springs springs;
  SpringBlocks blocks;
  Forces forces;
  Dynamics dynamics;
  Glue glue;
  deform::Environment environment;
  std::vector<uint32_t> active, active_springs;
  std::vector<deform::PointLoad> loads;

  deform::Membrane membrane() {
    deform::Membrane m{particles, springs, blocks, forces, dynamics};
    if (!glue.x.empty()) m.glue = &glue;
    m.environment = &environment;
    m.active = active;
    m.active_springs = active_springs;
    m.loads = loads;
    return m;
  }
};

inline uint32_t add_particle(Body& b, double x, double y, double z, ParticleKind kind,
                             double mass_kg) {
  const uint32_t i = table_add(b.particles);
  b.particles.x[i] = static_cast<float>(x), b.particles.y[i] = static_cast<float>(y);
  b.particles.z[i] = static_cast<float>(z);
  b.particles.vx[i] = b.particles.vy[i] = b.particles.vz[i] = 0.0f;
  b.particles.kind[i] = kind;
  b.particles.inv_mass[i] =
      kind == ParticleKind::Anchored ? 0.0f : static_cast<float>(1.0 / mass_kg);
  return i;
}

// Anchor at the origin, one free particle at (1 + stretch, 0, 0) on a spring of rest length 1 mm.
inline Body make_spring_mass(double k_mn_mm, double mass_kg, double stretch_mm) {
  Body b;
  add_particle(b, 0, 0, 0, ParticleKind::Anchored, 0);
  add_particle(b, 1.0 + stretch_mm, 0, 0, ParticleKind::Free, mass_kg);
  const uint32_t e = table_add(b.springs);
  b.springs.i[e] = 0, b.springs.j[e] = 1, b.springs.rest_length[e] = 1.0f;
  b.springs.stiffness[e] = static_cast<float>(k_mn_mm);
  b.blocks = springs::plan_blocks(b.springs, 2);
  b.forces.resize_zero(2);
  return b;
}

inline void finish(Body& b, const springs::SpringMaterial& material) {
  b.springs = springs::build_springs(b.particles, b.triangles, material);
  b.blocks = springs::plan_blocks(b.springs, b.particles.slots.size());
  b.forces.resize_zero(b.particles.slots.size());
  b.dynamics.law = material.law;
}

// n × n nodes `spacing` apart in z = 0, centred on the origin, each square split by a diagonal;
// rim anchored (unless `pinned` is false), the others free with mass `mass_kg`. Node (r, c) = r·n +
// c.
inline Body make_grid(int n, double spacing, double mass_kg,
                      const springs::SpringMaterial& material, bool pinned = true) {
  Body b;
  const double half = 0.5 * (n - 1) * spacing;
  for (int r = 0; r < n; ++r)
    for (int c = 0; c < n; ++c) {
      const bool rim = pinned && (r == 0 || c == 0 || r == n - 1 || c == n - 1);
      add_particle(b, c * spacing - half, r * spacing - half, 0,
                   rim ? ParticleKind::Anchored : ParticleKind::Free, mass_kg);
    }
  for (int r = 0; r + 1 < n; ++r)
    for (int c = 0; c + 1 < n; ++c) {
      const uint32_t v00 = r * n + c, v01 = v00 + 1, v10 = v00 + n, v11 = v10 + 1;
      for (auto tri :
           {std::array<uint32_t, 3>{v00, v01, v11}, std::array<uint32_t, 3>{v00, v11, v10}}) {
        const uint32_t t = table_add(b.triangles);
        b.triangles.a[t] = tri[0], b.triangles.b[t] = tri[1], b.triangles.c[t] = tri[2];
      }
    }
  finish(b, material);
  return b;
}

constexpr double kCapsuleThicknessMm = 0.013;
constexpr double kCapsuleDensityKgMm3 = 1.0e-6;  // 1000 kg/m³

// The anterior capsule at `level`, rim anchored, lumped mass ρ·h·A/3 per triangle corner.
inline Body make_capsule(int level, double youngs_kpa = 2000.0, double prestretch = 0.0) {
  const SurfaceMesh mesh = eye::make_capsule(
      eye::default_eye_params(), eye::resolution_for_level(level), eye::CapsuleLayout::Curvilinear);
  Body b;
  const uint32_t n = static_cast<uint32_t>(mesh.vertices.size());
  std::vector<double> mass(n, 0.0);
  std::vector<std::pair<uint64_t, int>> edges;
  for (const auto& tri : mesh.triangles) {
    const uint32_t t = table_add(b.triangles);
    b.triangles.a[t] = tri[0], b.triangles.b[t] = tri[1], b.triangles.c[t] = tri[2];
    const double area = 0.5 * (mesh.vertices[tri[1]] - mesh.vertices[tri[0]])
                                  .cross(mesh.vertices[tri[2]] - mesh.vertices[tri[0]])
                                  .norm();
    for (uint32_t v : tri) mass[v] += kCapsuleDensityKgMm3 * kCapsuleThicknessMm * area / 3.0;
    for (int k = 0; k < 3; ++k) {
      const uint64_t a = std::min(tri[k], tri[(k + 1) % 3]), c = std::max(tri[k], tri[(k + 1) % 3]);
      edges.push_back({a << 32 | c, 1});
    }
  }
  std::sort(edges.begin(), edges.end());
  std::vector<uint8_t> rim(n, 0);
  for (size_t i = 0; i < edges.size();) {
    size_t j = i;
    while (j < edges.size() && edges[j].first == edges[i].first) ++j;
    if (j - i == 1) rim[edges[i].first >> 32] = rim[edges[i].first & 0xffffffffu] = 1;
    i = j;
  }
  for (uint32_t i = 0; i < n; ++i) {
    const Vec3& v = mesh.vertices[i];
    add_particle(b, v.x(), v.y(), v.z(), rim[i] ? ParticleKind::Anchored : ParticleKind::Free,
                 mass[i]);
  }
  finish(b, {.sheet_modulus_mn_mm = youngs_kpa * kCapsuleThicknessMm, .prestretch = prestretch});
  return b;
}

// Index of the free particle nearest the z axis.
inline uint32_t centre_particle(const Body& b) {
  uint32_t best = 0;
  double best_r = 1e30;
  for (uint32_t i = 0; i < b.particles.slots.size(); ++i) {
    const double r = std::hypot(b.particles.x[i], b.particles.y[i]);
    if (b.particles.kind[i] == ParticleKind::Free && r < best_r) best = i, best_r = r;
  }
  return best;
}

using test::all_finite;
using test::hash_state;

inline double max_speed(const Particles& p) {
  double s = 0.0;
  for (uint32_t i = 0; i < p.slots.size(); ++i)
    s = std::max(s, std::sqrt(double{p.vx[i]} * p.vx[i] + double{p.vy[i]} * p.vy[i] +
                              double{p.vz[i]} * p.vz[i]));
  return s;
}

}  // namespace phaco::deform_test
