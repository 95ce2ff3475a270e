#pragma once
// Membrane invariants after a topology change (issue 4, item 4): the check that cutting and
// tearing must never break, called by the tests after every cut or tear step and by debug builds
// once per frame.
//
// Over the alive elements only (SlotIndex::alive; tombstones are skipped, never reported):
//  - indices in range, no alive triangle or spring referring to a dead particle;
//  - finite particle positions and velocities, finite non-negative spring rest length/stiffness;
//  - no triangle with a repeated vertex, an area below min_area_mm2 or an angle below
//    min_angle_deg;
//  - every edge used by at most two triangles, and an interior edge traversed in opposite
//    directions by its two triangles (consistent orientation);
//  - every vertex manifold: its triangles, joined through the edges they share at it, form one
//    fan. With every edge on at most two triangles, one fan is one disc (interior vertex) or one
//    half-disc (boundary vertex); two fans touching only at the vertex (a bowtie) are what a cut's
//    vertex duplication must never leave, and the edge checks alone cannot see them;
//  - the spring set equals the edge set, as unordered particle pairs, with no duplicate spring and
//    i < j in every spring (components/springs.hpp).
//
// How: the three directed edges of every valid triangle go into one array keyed by the unordered
// pair, sorted (counting sort on the lower particle, then by the upper: O(n), no hashing,
// deterministic) and walked once; the alive springs' pairs are sorted the same way and merged
// against the distinct edges. The same walk joins, across each shared edge, the two triangles'
// corners at its ends (union-find over corners 3·triangle + k); a vertex whose corners end in more
// than one set is a bowtie. Scratch arrays live in
// InvariantScratch so a caller that checks every frame allocates nothing once warmed up (only a
// violation's record allocates). Single-threaded; timings in docs/topology_invariants.md.
//
// Why not engine/core/mesh_checks: check_surface counts properties of a SurfaceMesh (dense, no
// tombstones, throws on a bad index) while this names each offending element of the live SoA
// tables; its edge-pair helpers are internal to that file, so the same sort-and-walk idea is used
// here over half-edges that also carry their triangle.
//
// Reads: particles (slots, x, y, z, vx, vy, vz), triangles, springs, spring blocks and graph.
// Writes: nothing.
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "components/particles.hpp"
#include "components/springs.hpp"
#include "components/triangles.hpp"

namespace phaco::topology_check {

// Debug builds run the check every frame; release builds only where a test or tool asks.
#ifdef NDEBUG
inline constexpr bool kCheckEveryFrame = false;
#else
inline constexpr bool kCheckEveryFrame = true;
#endif

struct InvariantThresholds {
  double min_area_mm2 = 1e-8;
  double min_angle_deg = 1.0;  // below 90
};

// What each record's `element` and `other` name (kInvalidIndex where there is nothing to name).
enum class Violation : uint8_t {
  IndexOutOfRange,         // element: triangle/spring (see table), other: the bad particle index;
                           // or a column shorter than the slots: element = first index lacking data
  DeadParticleReferenced,  // element: triangle/spring, other: the dead particle
  NonFinitePosition,       // element: particle (position or velocity NaN/inf)
  DegenerateTriangle,      // element: triangle with a repeated vertex, other: that vertex
  EdgeWithMoreThanTwoTriangles,  // element: highest-index triangle on the edge, other: lowest
  InconsistentOrientation,  // element: the triangle that disagrees with most of its neighbours,
                            // other: one neighbour across a same-direction edge
  SmallArea,                // element: triangle
  SmallAngle,               // element: triangle, other: the corner particle with the small angle
  SpringWithoutEdge,        // element: spring
  EdgeWithoutSpring,        // element: lowest-index triangle with the edge
  DuplicateSpring,          // element: the later spring, other: the first spring with that pair
  SpringIndexOrder,         // element: spring with i >= j
  NonFiniteSpring,          // element: spring whose rest length or stiffness is NaN/inf/negative
  NonManifoldVertex,        // element: particle whose triangles form more than one fan (a bowtie),
                            // other: a triangle outside the fan of its lowest-index triangle
};
inline constexpr int kViolationKinds = 14;

std::string_view to_string(Violation v);

enum class ElementTable : uint8_t { Particle, Triangle, Spring };
std::string_view to_string(ElementTable t);

struct ViolationRecord {
  Violation kind;
  uint32_t element;    // triangle, spring or particle index (see `table`)
  uint32_t other;      // see Violation; kInvalidIndex if none
  std::string detail;  // human-readable: the pair, the angle, the area...
  ElementTable table;  // which table `element` indexes
};

struct InvariantReport {
  std::vector<ViolationRecord> violations;
  size_t checked_triangles = 0;  // alive
  size_t checked_springs = 0;    // alive
  size_t checked_particles = 0;  // alive

  bool ok() const { return violations.empty(); }
  size_t count(Violation v) const;
  // First line: totals per kind ("3 violations: 2 InconsistentOrientation, 1 SmallAngle"), then
  // up to max_lines records, then "... and N more".
  std::string summary(size_t max_lines = 10) const;
};

// Reused between calls so a per-frame check does not allocate.
struct InvariantScratch {
  struct HalfEdge {
    uint64_t key;  // (min << 32) | max
    uint32_t triangle;
    uint32_t forward;  // 1 if traversed min -> max
  };
  struct SpringKey {
    uint64_t key;
    uint32_t spring;
  };
  struct Pair {
    uint32_t t0, t1;
  };
  std::vector<HalfEdge> half_edges, sorted_half_edges;
  std::vector<SpringKey> spring_keys, sorted_spring_keys;
  std::vector<uint32_t> bucket;         // per particle: counting-sort offsets
  std::vector<HalfEdge> edges;          // distinct edges, with their lowest-index triangle
  std::vector<Pair> inconsistent;       // triangle pairs across a same-direction interior edge
  std::vector<uint8_t> interior_count;  // per triangle slot: interior (two-triangle) edges
  std::vector<uint8_t> bad_count;       // per triangle slot: same-direction interior edges
  std::vector<uint8_t> blamed;          // per triangle slot
  std::vector<uint8_t> valid;           // per triangle slot: alive, indices good, no repeat
  std::vector<uint32_t> corner_set;     // per corner 3·t + k: union-find parent
  std::vector<uint32_t> fans;           // per particle: fans (corner sets) around it
};

InvariantReport check_membrane(const Particles& particles, const Triangles& triangles,
                               const Springs& springs, const InvariantThresholds& thresholds,
                               InvariantScratch& scratch);

// Same, with a scratch of its own (allocates).
InvariantReport check_membrane(const Particles& particles, const Triangles& triangles,
                               const Springs& springs, const InvariantThresholds& thresholds = {});

// The force blocks and the spring graph against the spring table, as a cut's incremental refresh
// leaves them (components/springs.hpp; O(S log S), for tests and debug runs):
//  - blocks: spring ranges start at 0, never decrease and end at the tail, which runs to the end
//    of the table, so a block pass visits every spring slot exactly once; every spring of planned
//    block b has i in b's particles and j in b's or the next block's (two blocks of one parity
//    never share a particle); a tombstone has stiffness 0 (the passes visit it);
//  - graph: one row per particle; each row, as a set of (neighbour, spring), is what a fresh build
//    from the live springs gives, and is sorted by neighbour.
// Returns "" if consistent, else the first problem found.
std::string check_spring_structure(const Springs& springs, const SpringBlocks& blocks,
                                   const SpringGraph& graph, uint32_t particle_count);

}  // namespace phaco::topology_check
