#pragma once
// Local topology edits of a membrane, the primitives seed 000 §5.2's cutting is made of: insert a
// cut point on an edge or inside a triangle (the mesh subdivision of Table 1's cases), open an
// edge of the cut path so the incision can gape (duplicating a vertex whose triangle fan the cut
// splits: "c_t is duplicated to give an identical copy c'_t", Fig. 4c; "the intersected springs
// are split"), and merge a triangle pair along the cut whose cut edges are nearly collinear (the
// local remeshing of Fig. 5a).
//
// Every edit is local: it reads and writes the few triangles around the edited feature, keeps
// the triangle adjacency, a per-particle triangle hint and the spring-per-edge index up to date
// by hand, and never scans a whole table, so its cost does not grow with the mesh.
//
// Springs keep the spring set equal to the edge set (systems/topology_check). New springs are
// appended to the table (the unplanned tail of components/springs.hpp's SpringBlocks); a removed
// spring is a tombstone whose stiffness is set to 0, so a force pass over the table that does not
// test liveness adds nothing for it. Their stiffness and
// rest length, and the particles' lumped masses, are recomputed for the touched region from the
// membrane's rest shape by the same formulas build_springs uses (seed 000 §5.1 area-weighted
// stiffness, pre-stretch), so a cut region carries the springs a fresh build of the cut mesh would
// give it; new points get their rest position by interpolation. With pre-stretch, the springs
// across a new free edge are no longer balanced and pull it open: "the cut is visually exposed due
// to the restoring forces in the pre-stretched springs" (seed 000 §5.2).
//
// A "slit": when a cut edge opens but neither end's fan splits (both ends are crack tips, e.g. the
// first segment of a cut inside the membrane) the two triangles stop being neighbours yet still
// share the edge and its spring. It opens as soon as an end gets a second cut edge or reaches the
// rim. Edits treat every triangle holding an edge's two ends as on that edge.
//
// Reads and writes: <body>.particles, <body>.triangles, <body>.springs, the MembraneTopology.
#include <array>
#include <cstdint>
#include <string>
#include <unordered_map>
#include <vector>

#include "components/particles.hpp"
#include "components/springs.hpp"
#include "components/triangles.hpp"
#include "systems/cut/cut_point.hpp"
#include "systems/springs/springs.hpp"

namespace phaco::cut {

// What the edits keep consistent beside the tables.
struct MembraneTopology {
  TriangleAdjacency adjacency;            // per triangle slot
  std::vector<uint32_t> vertex_triangle;  // per particle slot: an alive triangle holding it
  std::unordered_map<uint64_t, uint32_t> spring_of_edge;  // edge_key(i, j) -> spring
  std::vector<double> rest_x, rest_y, rest_z;             // per particle slot: rest shape, mm
  // Springs the edits added and removed since the owner of the physics last caught up (it clears
  // them): the spring graph is patched from these, not rebuilt (springs::patch_spring_graph).
  // Added springs are appended to the table, never put in a freed slot, so a spring index is not
  // reused before the next compaction (compact_and_sort_springs clears both lists).
  std::vector<uint32_t> added_springs, removed_springs;
};

inline uint64_t edge_key(uint32_t i, uint32_t j) {
  return i < j ? (uint64_t{i} << 32) | j : (uint64_t{j} << 32) | i;
}

struct MembraneMaterial {
  springs::SpringMaterial springs;
  double areal_density_kg_mm2 =
      0.0;  // ρ·h; masses lumped as ρ·h·area/3 per corner; 0: masses untouched
};

// The tables an edit changes, together.
struct CutMesh {
  Particles& particles;
  Triangles& triangles;
  Springs& springs;
  MembraneTopology& topology;
  const MembraneMaterial& material;
};

// What edits did since the log was last cleared: for re-springing, the physics' per-particle
// arrays, force-propagation sources and the figures.
// How a new particle's state was made: the weighted sum of up to three particles' states (a copy
// has one weight 1). A caller keeping positions elsewhere (the scene cuts in the rest shape, see
// procedures/scene/capsule_cutting.hpp) replays these in order to place the new particles.
struct ParticleOrigin {
  uint32_t particle = kInvalidIndex;
  std::array<uint32_t, 3> from{kInvalidIndex, kInvalidIndex, kInvalidIndex};
  std::array<double, 3> weight{0.0, 0.0, 0.0};
};

struct EditLog {
  std::vector<uint32_t> new_particles;      // inserted cut points and duplicated copies
  std::vector<ParticleOrigin> origins;      // one per new particle, in creation order
  std::vector<uint32_t> removed_particles;  // by remeshing
  std::vector<uint32_t> touched_triangles;  // created or changed (may repeat; may have died since)
  uint32_t edge_splits = 0, face_splits = 0, opened_edges = 0, duplicated_vertices = 0, merges = 0;
  uint32_t clamped_pretension = 0;  // springs given the uniform pre-stretch (sliver) on refresh
  void clear();
};

// Builds the topology of a membrane whose rest shape is its current shape. Throws
// std::invalid_argument when the springs are not the edge set (check_membrane first) or a
// triangle is invalid.
MembraneTopology build_topology(const Particles& particles, const Triangles& triangles,
                                const Springs& springs);

// Alive triangles holding both a and b (one or two; more only on a broken mesh), sorted.
void triangles_on_edge(const CutMesh& m, uint32_t a, uint32_t b, std::vector<uint32_t>& out);

// True if (a, b) is an edge whose two triangles are still neighbours across it: it can be cut or
// torn along (not the rim, not an opened cut, not a slit).
bool joined_edge(const CutMesh& m, uint32_t a, uint32_t b);

// True if v lies on the membrane's boundary (rim or an opened cut): its fan is open.
bool on_boundary(const CutMesh& m, uint32_t v);

// Reserves room for `extra_particles` more particles (and about twice as many triangles, three
// times as many springs) in every table and topology array, so that cutting does not reallocate
// whole columns — a cost proportional to the mesh — in the middle of a frame.
void reserve_for_cuts(CutMesh& m, uint32_t extra_particles);

// Inserts a particle at (1-t)·a + t·b on edge (a, b), 0 < t < 1, splitting every triangle on the
// edge in two. Returns the new particle.
uint32_t split_edge(CutMesh& m, uint32_t a, uint32_t b, double t, EditLog& log);

// Inserts a particle at barycentric weights `bary` (of corners a, b, c) inside triangle `tri`,
// splitting it in three. Returns the new particle.
uint32_t split_face(CutMesh& m, uint32_t tri, const Vec3& bary, EditLog& log);

// Opens edge (p, q) of the cut path: its triangles stop being neighbours, and an end whose fan
// this splits is duplicated (the copy takes the triangles on the right of p -> q). Returns false
// if the edge was already open (or not an edge).
bool open_edge(CutMesh& m, uint32_t p, uint32_t q, EditLog& log);

// Seed 000 Fig. 5a: if boundary particle v has exactly two triangles, (m1, v, x) and (v, m2, x),
// with both (m1, v) and (v, m2) on the boundary and turning by less than max_turn_deg, and the
// merged triangle (m1, m2, x) keeps its orientation and every angle at least min_angle_deg, they
// merge and v is removed. Anchored or scripted particles are never removed. Returns true if merged.
bool merge_along_cut(CutMesh& m, uint32_t v, double max_turn_deg, double min_angle_deg,
                     EditLog& log);

// Recomputes stiffness and rest length of every spring on an edge of a touched triangle, and the
// masses of their corners (anchored particles keep inverse mass 0). Call after a batch of edits.
void refresh_region(CutMesh& m, EditLog& log);

// refresh_region over the triangles the log touched since it held `touched_before` of them (as
// the cutter and the forceps do after a segment or a grasp), adding its clamped pretension to log.
void refresh_since(CutMesh& m, EditLog& log, size_t touched_before);

// The MembraneTopology against the tables, rebuilt from scratch (O(n log n), for tests and debug
// builds): every live link names a live triangle across the same edge, and is what a fresh
// adjacency gives except across opened cut edges and slits; every particle's hint holds it; the
// spring index is the live spring set. Returns "" if consistent, else the first problem found.
std::string check_topology(const CutMesh& m);

// Smallest angle (degrees) of the triangle, and the one the same corners make in the rest shape.
double min_angle_deg(const Vec3& p0, const Vec3& p1, const Vec3& p2);
Vec3 rest_position(const MembraneTopology& topo, uint32_t v);

}  // namespace phaco::cut
