#pragma once
// The particle and triangle tables of a body built from a mesh's vertices and triangles: the one
// conversion the scene, the cut's membrane sheet and the tests all use; and a tetrahedral body's
// tables back to a mesh (what the lens systems build their topology from).
#include <cstdint>
#include <vector>

#include "components/particles.hpp"
#include "components/tets.hpp"
#include "components/triangles.hpp"
#include "engine/core/math.hpp"
#include "engine/core/mesh_data.hpp"

namespace phaco {

// One particle per vertex, at rest, of the given kind and inverse mass.
inline Particles particles_at(const std::vector<Vec3>& vertices, ParticleKind kind,
                              float inv_mass) {
  Particles p;
  table_append(p, static_cast<uint32_t>(vertices.size()));
  for (size_t i = 0; i < vertices.size(); ++i) {
    p.x[i] = static_cast<float>(vertices[i].x());
    p.y[i] = static_cast<float>(vertices[i].y());
    p.z[i] = static_cast<float>(vertices[i].z());
    p.inv_mass[i] = inv_mass;
    p.kind[i] = kind;
  }
  return p;
}

inline Triangles triangles_of(const SurfaceMesh& mesh) {
  Triangles t;
  table_append(t, static_cast<uint32_t>(mesh.triangles.size()));
  for (size_t k = 0; k < mesh.triangles.size(); ++k) {
    t.a[k] = mesh.triangles[k][0];
    t.b[k] = mesh.triangles[k][1];
    t.c[k] = mesh.triangles[k][2];
  }
  return t;
}

// The mesh of a tetrahedral body's tables (every slot, live or not, in table order).
inline TetMesh tet_mesh_of(const Particles& p, const Tets& tets) {
  TetMesh mesh;
  mesh.vertices.reserve(p.x.size());
  for (size_t i = 0; i < p.x.size(); ++i) mesh.vertices.emplace_back(p.x[i], p.y[i], p.z[i]);
  mesh.tets.reserve(tets.a.size());
  for (size_t t = 0; t < tets.a.size(); ++t)
    mesh.tets.push_back({tets.a[t], tets.b[t], tets.c[t], tets.d[t]});
  mesh.region = tets.region;
  return mesh;
}

}  // namespace phaco
