#include "perf/membrane_fixture.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <utility>

#include "engine/schedule/parallel.hpp"
#include "procedures/eye/eye_mesh.hpp"
#include "systems/springs/springs.hpp"

namespace phaco::perf {

namespace {

// Blocks of at least ~4096 particles: a block's springs then outweigh the task overhead, and a
// mesh too small for two such blocks runs the spring pass serially (a mesh-size choice, never the
// thread count, so results stay bit-identical across thread counts).
uint32_t target_blocks(uint32_t particles) {
  return std::max<uint32_t>(1, particles / 4096);
}

}  // namespace

double MembraneFixture::stable_dt(double safety) const {
  return max_k_over_m > 0 ? safety * 2.0 / std::sqrt(max_k_over_m) : 0.0;
}

MembraneFixture make_membrane_fixture(const FixtureOptions& o) {
  MembraneFixture m;
  m.options = o;
  const SurfaceMesh mesh =
      eye::make_capsule(eye::default_eye_params(), eye::resolution_for_level(o.level),
                        eye::CapsuleLayout::Curvilinear);
  const uint32_t n = static_cast<uint32_t>(mesh.vertices.size());
  table_append(m.particles, n);
  for (uint32_t v = 0; v < n; ++v) {
    m.particles.x[v] = static_cast<float>(mesh.vertices[v].x());
    m.particles.y[v] = static_cast<float>(mesh.vertices[v].y());
    m.particles.z[v] = o.flat ? 0.0f : static_cast<float>(mesh.vertices[v].z());
  }
  table_append(m.triangles, static_cast<uint32_t>(mesh.triangles.size()));
  // Boundary edges belong to one triangle only; their vertices form the rim.
  std::map<std::pair<uint32_t, uint32_t>, int> edge_use;
  std::vector<double> mass(n, 0.0);
  const double areal_density = o.density_kg_m3 * 1e-9 * o.thickness_mm;  // kg/mm²
  for (uint32_t t = 0; t < mesh.triangles.size(); ++t) {
    const auto& tri = mesh.triangles[t];
    m.triangles.a[t] = tri[0], m.triangles.b[t] = tri[1], m.triangles.c[t] = tri[2];
    const Vec3 p[3] = {Vec3(m.particles.x[tri[0]], m.particles.y[tri[0]], m.particles.z[tri[0]]),
                       Vec3(m.particles.x[tri[1]], m.particles.y[tri[1]], m.particles.z[tri[1]]),
                       Vec3(m.particles.x[tri[2]], m.particles.y[tri[2]], m.particles.z[tri[2]])};
    const double area = 0.5 * (p[1] - p[0]).cross(p[2] - p[0]).norm();
    for (int k = 0; k < 3; ++k) {
      mass[tri[k]] += areal_density * area / 3.0;
      ++edge_use[{std::min(tri[k], tri[(k + 1) % 3]), std::max(tri[k], tri[(k + 1) % 3])}];
    }
  }
  std::vector<uint8_t> on_rim(n, 0);
  for (const auto& [e, uses] : edge_use) {
    if (uses == 1) on_rim[e.first] = on_rim[e.second] = 1;
  }
  double best_r = 1e30;
  for (uint32_t v = 0; v < n; ++v) {
    const double r = std::hypot(m.particles.x[v], m.particles.y[v]);
    if (r < best_r) best_r = r, m.centre = v;
    m.total_mass_kg += mass[v];
    if (on_rim[v]) {
      m.rim.push_back(v);
      m.radius_mm = std::max(m.radius_mm, r);
      m.particles.kind[v] = ParticleKind::Anchored;
      m.particles.inv_mass[v] = 0.0f;
    } else {
      m.particles.kind[v] = ParticleKind::Free;
      m.particles.inv_mass[v] = static_cast<float>(1.0 / mass[v]);
    }
  }
  springs::SpringMaterial mat;
  mat.law = o.law;
  mat.weighting = o.weighting;
  mat.sheet_modulus_mn_mm = o.youngs_modulus_kpa * o.thickness_mm;
  mat.prestretch = o.prestretch;
  m.springs = springs::build_springs(m.particles, m.triangles, mat);
  m.blocks = springs::plan_blocks(m.springs, n, target_blocks(n));
  m.forces.resize_zero(n);
  double sum = 0;
  for (float r : m.springs.rest_length) sum += r;
  m.mean_edge_mm =
      m.springs.slots.size() ? sum / m.springs.slots.size() / (1.0 - o.prestretch) : 0.0;
  m.max_k_over_m = springs::max_stiffness_over_mass(m.springs, m.particles);
  return m;
}

double hot_bytes_per_vertex() {
  return 7 * sizeof(float) + sizeof(ParticleKind) + 3 * sizeof(float);  // 29 particle + 12 force
}

double hot_bytes_per_spring() {
  return 2 * sizeof(uint32_t) + 2 * sizeof(float);
}

double spring_pass_bytes(uint32_t vertices, uint32_t springs) {
  // Springs read once; positions read and forces read+written, each at least once per vertex.
  return springs * hot_bytes_per_spring() + vertices * (3 * 4.0 + 2 * 3 * 4.0);
}

double plain_step_bytes(uint32_t vertices, uint32_t springs) {
  // Spring pass, then the node pass reads x, v, inv_mass, f and writes x, v, f.
  return spring_pass_bytes(vertices, springs) + vertices * (7 * 4.0 + 3 * 4.0 + 6 * 4.0 + 3 * 4.0);
}

void integrate_nodes(Particles& p, Forces& f, float dt, float damping) {
  const uint32_t n = p.slots.size();
  parallel_for(0, n, 4096, [&](uint32_t begin, uint32_t end, int) {
    float* __restrict x = p.x.data();
    float* __restrict y = p.y.data();
    float* __restrict z = p.z.data();
    float* __restrict vx = p.vx.data();
    float* __restrict vy = p.vy.data();
    float* __restrict vz = p.vz.data();
    const float* __restrict im = p.inv_mass.data();
    float* __restrict fx = f.fx.data();
    float* __restrict fy = f.fy.data();
    float* __restrict fz = f.fz.data();
    const float keep = 1.0f - dt * damping;
    for (uint32_t v = begin; v < end; ++v) {
      const float s = dt * im[v];
      vx[v] = keep * vx[v] + s * fx[v];
      vy[v] = keep * vy[v] + s * fy[v];
      vz[v] = keep * vz[v] + s * fz[v];
      x[v] += dt * vx[v];
      y[v] += dt * vy[v];
      z[v] += dt * vz[v];
      fx[v] = 0.0f, fy[v] = 0.0f, fz[v] = 0.0f;
    }
  });
}

void plain_step(MembraneFixture& m, float dt, float damping, uint32_t load_node, float load_z_mn) {
  if (load_z_mn != 0.0f && load_node < m.vertex_count()) m.forces.fz[load_node] += load_z_mn;
  springs::add_spring_forces(m.springs, m.blocks, m.options.law, m.particles, m.forces);
  integrate_nodes(m.particles, m.forces, dt, damping);
}

}  // namespace phaco::perf
