#pragma once
// Test support: a SurfaceMesh as the flat particle and triangle tables the systems work on.
#include "components/from_mesh.hpp"
#include "engine/core/mesh_data.hpp"

namespace phaco::test {

inline Particles particles_from(const SurfaceMesh& mesh, float inv_mass = 1.0f) {
  return particles_at(mesh.vertices, ParticleKind::Free, inv_mass);
}

inline Triangles triangles_from(const SurfaceMesh& mesh) {
  return triangles_of(mesh);
}

}  // namespace phaco::test
