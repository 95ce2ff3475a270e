#pragma once
// A membrane that owns what the cut edits — particles, triangles, springs, topology and material —
// built from a surface mesh, for the scripted procedures, the perf harness and the tests. The
// scene keeps the same tables in its own components and builds a CutMesh over them.
//
// Particles start at the mesh vertices, at rest, free; masses are lumped from the areas
// (areal_density·A/3 per corner) when the material has a density, else inverse mass 1.
#include <algorithm>

#include "components/from_mesh.hpp"
#include "engine/core/mesh_data.hpp"
#include "systems/cut/membrane_edit.hpp"

namespace phaco::cut {

struct MembraneSheet {
  Particles particles;
  Triangles triangles;
  Springs springs;
  MembraneTopology topology;
  MembraneMaterial material;

  // References into this sheet: keep the sheet where it is while the CutMesh is used.
  CutMesh mesh() { return {particles, triangles, springs, topology, material}; }
};

inline MembraneSheet make_membrane_sheet(const SurfaceMesh& mesh,
                                         const MembraneMaterial& material) {
  MembraneSheet s;
  s.material = material;
  s.particles = particles_at(mesh.vertices, ParticleKind::Free, 1.0f);
  s.triangles = triangles_of(mesh);
  s.springs = springs::build_springs(s.particles, s.triangles, s.material.springs);
  s.topology = build_topology(s.particles, s.triangles, s.springs);
  {
    CutMesh m = s.mesh();
    reserve_for_cuts(m, std::max<uint32_t>(4096, s.particles.slots.size() / 4));
  }
  if (material.areal_density_kg_mm2 > 0) {
    EditLog all;
    for (uint32_t t = 0; t < s.triangles.slots.size(); ++t) all.touched_triangles.push_back(t);
    CutMesh m = s.mesh();
    refresh_region(m, all);  // also recomputes the springs, to the same values build_springs gave
  }
  return s;
}

}  // namespace phaco::cut
