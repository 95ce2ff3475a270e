#pragma once
// Membranes for the implicit-integrator tests: a pinned square grid patch and the capsule with its
// published material (E = 2 MPa, h = 0.013 mm, ρ = 1000 kg/m³).
#include <cmath>
#include <cstring>
#include <vector>

#include "procedures/eye/eye_mesh.hpp"
#include "systems/deform/implicit.hpp"
#include "systems/springs/springs.hpp"
#include "tests/support/particle_checks.hpp"

namespace phaco::implicit_test {

struct Body {
  Particles particles;
  Triangles triangles;
  Springs springs;
  SpringBlocks blocks;
  Forces forces;
  Dynamics dynamics;
  std::vector<uint32_t> active, active_springs;

  deform::Membrane membrane() {
    deform::Membrane m{particles, springs, blocks, forces, dynamics};
    m.active = active;
    m.active_springs = active_springs;
    return m;
  }
};

inline void finish(Body& b, const springs::SpringMaterial& material) {
  b.springs = springs::build_springs(b.particles, b.triangles, material);
  b.blocks = springs::plan_blocks(b.springs, b.particles.slots.size());
  b.forces.resize_zero(b.particles.slots.size());
  b.dynamics.law = material.law;
}

// n × n nodes, `spacing` apart, centred on the origin in z = 0; each square split by a diagonal;
// rim anchored, interior free with mass `mass_kg`. Node (r, c) is r·n + c.
inline Body make_grid(int n, double spacing, double mass_kg,
                      const springs::SpringMaterial& material) {
  Body b;
  table_append(b.particles, static_cast<uint32_t>(n * n));
  const double half = 0.5 * (n - 1) * spacing;
  for (int r = 0; r < n; ++r)
    for (int c = 0; c < n; ++c) {
      const uint32_t i = static_cast<uint32_t>(r * n + c);
      b.particles.x[i] = static_cast<float>(c * spacing - half);
      b.particles.y[i] = static_cast<float>(r * spacing - half);
      b.particles.z[i] = 0.0f;
      const bool rim = r == 0 || c == 0 || r == n - 1 || c == n - 1;
      b.particles.kind[i] = rim ? ParticleKind::Anchored : ParticleKind::Free;
      b.particles.inv_mass[i] = rim ? 0.0f : static_cast<float>(1.0 / mass_kg);
    }
  for (int r = 0; r + 1 < n; ++r)
    for (int c = 0; c + 1 < n; ++c) {
      const uint32_t v00 = r * n + c, v01 = v00 + 1, v10 = v00 + n, v11 = v10 + 1;
      for (auto [a, bb, cc] :
           {std::array<uint32_t, 3>{v00, v01, v11}, std::array<uint32_t, 3>{v00, v11, v10}}) {
        const uint32_t t = table_add(b.triangles);
        b.triangles.a[t] = a, b.triangles.b[t] = bb, b.triangles.c[t] = cc;
      }
    }
  finish(b, material);
  return b;
}

// The anterior capsule at `level`, rim anchored, lumped mass ρ·h·A/3 per triangle corner.
inline Body make_capsule(int level, double youngs_kpa = 2000.0, double prestretch = 0.0) {
  const SurfaceMesh mesh = eye::make_capsule(
      eye::default_eye_params(), eye::resolution_for_level(level), eye::CapsuleLayout::Curvilinear);
  Body b;
  const uint32_t n = static_cast<uint32_t>(mesh.vertices.size());
  table_append(b.particles, n);
  table_append(b.triangles, static_cast<uint32_t>(mesh.triangles.size()));
  std::vector<double> mass(n, 0.0);
  constexpr double kDensityKgMm3 = 1.0e-6, kThicknessMm = 0.013;
  for (size_t t = 0; t < mesh.triangles.size(); ++t) {
    const auto& tri = mesh.triangles[t];
    b.triangles.a[t] = tri[0], b.triangles.b[t] = tri[1], b.triangles.c[t] = tri[2];
    const double area = 0.5 * (mesh.vertices[tri[1]] - mesh.vertices[tri[0]])
                                  .cross(mesh.vertices[tri[2]] - mesh.vertices[tri[0]])
                                  .norm();
    for (uint32_t v : tri) mass[v] += kDensityKgMm3 * kThicknessMm * area / 3.0;
  }
  for (uint32_t i = 0; i < n; ++i) {
    b.particles.x[i] = static_cast<float>(mesh.vertices[i].x());
    b.particles.y[i] = static_cast<float>(mesh.vertices[i].y());
    b.particles.z[i] = static_cast<float>(mesh.vertices[i].z());
  }
  springs::SpringMaterial material{.sheet_modulus_mn_mm = youngs_kpa * kThicknessMm,
                                   .prestretch = prestretch};
  finish(b, material);
  // Rim: vertices of edges used by one triangle only.
  std::vector<int> count(b.springs.slots.size(), 0);
  for (size_t t = 0; t < mesh.triangles.size(); ++t)
    for (int k = 0; k < 3; ++k) {
      const uint32_t a = std::min(mesh.triangles[t][k], mesh.triangles[t][(k + 1) % 3]);
      const uint32_t c = std::max(mesh.triangles[t][k], mesh.triangles[t][(k + 1) % 3]);
      // Springs are sorted by (i, j): find the edge by binary search.
      uint32_t lo = 0, hi = b.springs.slots.size();
      while (lo < hi) {
        const uint32_t mid = (lo + hi) / 2;
        if (b.springs.i[mid] < a || (b.springs.i[mid] == a && b.springs.j[mid] < c))
          lo = mid + 1;
        else
          hi = mid;
      }
      ++count[lo];
    }
  std::vector<uint8_t> rim(n, 0);
  for (uint32_t e = 0; e < count.size(); ++e)
    if (count[e] == 1) rim[b.springs.i[e]] = rim[b.springs.j[e]] = 1;
  for (uint32_t i = 0; i < n; ++i) {
    b.particles.kind[i] = rim[i] ? ParticleKind::Anchored : ParticleKind::Free;
    b.particles.inv_mass[i] = rim[i] ? 0.0f : static_cast<float>(1.0 / mass[i]);
  }
  return b;
}

// Kinetic + elastic + gravitational energy, µJ (kg·mm²/s² = mN·mm = µJ).
inline double total_energy(const Body& b) {
  double e = springs::spring_energy(b.springs, b.dynamics.law, b.particles);
  const Particles& p = b.particles;
  for (uint32_t i = 0; i < p.slots.size(); ++i) {
    if (p.inv_mass[i] <= 0.0f) continue;
    const double m = 1.0 / p.inv_mass[i];
    e += 0.5 * m *
         (double(p.vx[i]) * p.vx[i] + double(p.vy[i]) * p.vy[i] + double(p.vz[i]) * p.vz[i]);
    e -= m * (b.dynamics.gravity_mm_s2[0] * p.x[i] + b.dynamics.gravity_mm_s2[1] * p.y[i] +
              b.dynamics.gravity_mm_s2[2] * p.z[i]);
  }
  return e;
}

using test::all_finite;
using test::hash_state;

}  // namespace phaco::implicit_test
