#pragma once
// Test support for cutting: a membrane (particles, triangles, springs, topology) that the cut
// systems edit, and the checks every cut test runs after every edit.
#include <gtest/gtest.h>

#include <string>

#include "engine/core/mesh_data.hpp"
#include "systems/cut/membrane_edit.hpp"
#include "systems/cut/membrane_sheet.hpp"
#include "systems/cut/progressive_cut.hpp"
#include "systems/springs/springs.hpp"
#include "systems/topology_check/topology_check.hpp"

namespace phaco::cut::test {

using CutSheet = MembraneSheet;

// The capsule's material (E·h = 26 mN/mm, ρ·h for 1000 kg/m³ and 13 µm) with a 5 % pre-stretch.
inline CutSheet cut_sheet(const SurfaceMesh& mesh, double prestretch = 0.05,
                          springs::Pretension pretension = springs::Pretension::Cotangent) {
  MembraneMaterial material;
  material.springs.sheet_modulus_mn_mm = 26.0;
  material.springs.prestretch = prestretch;
  material.springs.pretension = pretension;
  material.areal_density_kg_mm2 = 1000.0 * 1e-9 * 0.013;
  return make_membrane_sheet(mesh, material);
}

// Item 4's invariants at their default thresholds (area ≥ 1e-8 mm², angles ≥ 1°) and the cut's own
// bookkeeping (adjacency, hints, spring index) against a rebuild.
inline ::testing::AssertionResult sound(CutSheet& s) {
  const auto report = topology_check::check_membrane(s.particles, s.triangles, s.springs);
  if (!report.ok()) return ::testing::AssertionFailure() << report.summary();
  const std::string topo = check_topology(s.mesh());
  if (!topo.empty()) return ::testing::AssertionFailure() << topo;
  return ::testing::AssertionSuccess();
}

}  // namespace phaco::cut::test
