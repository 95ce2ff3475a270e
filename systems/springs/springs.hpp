#pragma once
// Springs of a membrane from its triangles, and the spring-force pass.
//
// Stiffness (seed 000 §5.1): k_e = c·(a1 + a2)/l², with a1, a2 the areas of the two triangles
// sharing edge e (one for a rim edge) and l its length. For an equilateral lattice this network
// has the 2D Young's modulus of a sheet with c = E·h (E Young's modulus, h thickness): a
// triangular spring lattice of stiffness k has E_2D = 2k/√3 and (a1 + a2)/l² = √3/2 there. In
// our units E in kPa = mN/mm², so c = E[kPa]·h[mm] is in mN/mm. Uniform weighting gives every
// spring that equilateral value, k = c·√3/2.
//
// Pre-stretch (seed 000 §5.2) puts the sheet under tension at rest, so a cut opens by itself. Two
// ways to choose the rest lengths:
//  - UniformPrestretch: rest = (1 − prestretch)·mesh length, as the seed says. On a mesh that is
//    not equilateral the resulting tension is not isotropic: on the capsule's rings and spokes the
//    hoop tension is 12 % above the radial one, and the analytic membrane test misses by 17.7 %
//    (docs/membrane_accuracy.md).
//  - Cotangent: rest lengths chosen so that spring e carries the tension t_e = T0·(cot α + cot
//  β)/2·l_e
//    (α, β the angles opposite e): the discrete form of an isotropic membrane stress T0·I, in
//    equilibrium as built on any triangulation. T0 = 1.5·prestretch·c, the equibiaxial tension of
//    a sheet of modulus c and Poisson ratio 1/3 (the triangular lattice's) stretched by prestretch.
//
// Reads: particles (x, y, z), triangles. Writes: springs; forces (accumulated).
#include <span>
#include <utility>
#include <vector>

#include "components/particles.hpp"
#include "components/springs.hpp"
#include "components/triangles.hpp"

namespace phaco::springs {

enum class Pretension : uint8_t { UniformPrestretch, Cotangent };

struct SpringMaterial {
  SpringLaw law = SpringLaw::Linear;
  StiffnessWeighting weighting = StiffnessWeighting::AreaWeighted;
  double sheet_modulus_mn_mm = 26.0;  // c = E·h: 2000 kPa × 0.013 mm for the capsule
  double prestretch = 0.0;            // fraction of the mesh length, 0 ≤ prestretch < 1
  // For the quadratic law, k_quad = k_linear / reference_extension_mm, so both laws give the same
  // force at that extension.
  double quadratic_reference_mm = 0.01;
  Pretension pretension = Pretension::UniformPrestretch;
};

// Stiffness and rest length of the spring on an edge of length `length` (mm) in the shape the
// springs are built from, whose
// one or two triangles have areas summing to area_sum and half the sum of the cotangents of the
// angles opposite the edge half_cot_sum. A cotangent rest length below half the edge (a sliver)
// is not used: the uniform pre-stretch is, and pretension_clamped says so. build_springs and the
// cut's local re-springing (systems/cut) share it, so a cut region gets the springs a fresh build
// would give it.
struct SpringConstants {
  double stiffness = 0.0;
  double rest_length = 0.0;
  bool pretension_clamped = false;
};
SpringConstants edge_spring_constants(const SpringMaterial& material, double length,
                                      double area_sum, double half_cot_sum);

// One spring per edge, sorted by (i, j); stiffness and rest length from the current positions.
// An edge whose cotangent tension would need a rest length below half the edge (an obtuse,
// badly shaped triangle, or a high pre-stretch on a coarse mesh: a bowed capsule at level 0)
// gets the uniform pre-stretch instead (edge_spring_constants), counted in *clamped_pretension
// when given. Throws std::invalid_argument for a prestretch outside [0, 1).
Springs build_springs(const Particles& particles, const Triangles& triangles,
                      const SpringMaterial& material, uint32_t* clamped_pretension = nullptr);

// Both directions of every alive spring, rows sorted by neighbour (independent of the spring
// table's order), each row with room for kGraphRowSlack more entries. Throws
// std::invalid_argument if a spring names a particle ≥ particle_count.
inline constexpr uint32_t kGraphRowSlack = 2;
SpringGraph build_spring_graph(const Springs& springs, uint32_t particle_count);

// Patches the graph after a cut or tear instead of rebuilding it: rows for particles up to
// particle_count (new rows empty), `removed` springs (tombstones; ends read from the table)
// taken out of their ends' rows, `added` springs that are still alive put in. Costs what the
// lists name, plus amortised growth of the arrays. Spring indices must not have been reused
// since they were added (the cut appends springs, components/springs.hpp). The result has the
// same rows, as sets, as build_spring_graph on the table (and the same order within each row).
void patch_spring_graph(SpringGraph& graph, const Springs& springs, uint32_t particle_count,
                        std::span<const uint32_t> removed, std::span<const uint32_t> added);

// Row p as a list of (neighbour, spring), in row order.
std::vector<std::pair<uint32_t, uint32_t>> graph_row(const SpringGraph& graph, uint32_t p);

// Partition for the parallel force pass; `target_blocks` is a mesh-size choice (e.g. 64), never
// the thread count. Falls back to fewer (at worst one) blocks when springs span far in index.
SpringBlocks plan_blocks(const Springs& springs, uint32_t particle_count,
                         uint32_t target_blocks = 64);

// Adds every spring's force to both ends: f_i += F·x̂, f_j −= F·x̂ with x̂ from i to j and
// F = k·(l − l0) (linear) or k·(l − l0)·|l − l0| (quadratic). Parallel over even then odd blocks,
// then the unplanned tail serially; bit-identical for any thread count.
void add_spring_forces(const Springs& springs, const SpringBlocks& blocks, SpringLaw law,
                       const Particles& particles, Forces& forces);

// Elastic energy, mN·mm = µJ (summed in a fixed order).
double spring_energy(const Springs& springs, SpringLaw law, const Particles& particles);

// Largest k/m over the particles (1/s²), the quantity that bounds an explicit step:
// ω_max² ≈ Σ_springs k / m at a particle.
double max_stiffness_over_mass(const Springs& springs, const Particles& particles);

}  // namespace phaco::springs
