#pragma once
// Test support: a SurfaceMesh as the flat particle and triangle tables the systems work on.
#include "components/particles.hpp"
#include "components/triangles.hpp"
#include "engine/core/mesh_data.hpp"

namespace phaco::test {

inline Particles particles_from(const SurfaceMesh& mesh, float inv_mass = 1.0f) {
  Particles p;
  table_append(p, static_cast<uint32_t>(mesh.vertices.size()));
  for (size_t i = 0; i < mesh.vertices.size(); ++i) {
    p.x[i] = static_cast<float>(mesh.vertices[i].x());
    p.y[i] = static_cast<float>(mesh.vertices[i].y());
    p.z[i] = static_cast<float>(mesh.vertices[i].z());
    p.inv_mass[i] = inv_mass;
  }
  return p;
}

inline Triangles triangles_from(const SurfaceMesh& mesh) {
  Triangles t;
  table_append(t, static_cast<uint32_t>(mesh.triangles.size()));
  for (size_t k = 0; k < mesh.triangles.size(); ++k) {
    t.a[k] = mesh.triangles[k][0];
    t.b[k] = mesh.triangles[k][1];
    t.c[k] = mesh.triangles[k][2];
  }
  return t;
}

}  // namespace phaco::test
