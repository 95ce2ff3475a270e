#pragma once
// Simplex cells of the lens (seed 002 §5.1 construction, §5.3 removal primitive) and the
// consistency check of their boundary against a rebuild from scratch.
//
// Construction, the seed's three loops:
//   1. over tets: centre, volume, and every face keyed by its sorted vertex triple;
//   2. over shared faces (a triple met twice): the internal connections both ways;
//   3. over non-shared faces: for each edge, the other boundary face on it (a boundary edge met
//      twice); where an edge carries more than two boundary faces (non-manifold, only after
//      removals), the rule below decides.
//
// Boundary link rule ("through the solid"): the partner of external face F across edge e is the
// external face reached by turning about e from F through alive cells: leave F's cell by its other
// face on e, enter the neighbour, and so on until a face with no neighbour. Each cell holds exactly
// two faces on each of its edges, so the walk is a path in the fan of tets around e; it pairs the
// two boundary faces that close one run of alive tets about e. On a manifold edge that is the only
// other boundary face; on a non-manifold one (two runs touching along e) each run keeps its own
// surface, as if the runs were pulled apart.
//
// Removal (seed Figs. 5–9) as one local rule. Removing cell c: its internal faces become external
// faces of its neighbours ("the internal connections deleted are substituted by external
// connections"); only boundary links about c's six edges can change, and each new external face
// takes, on each of its three edges, the partner found by the walk above (and the partner links
// back). On the seed's cases:
//   - three external faces (Fig. 5): the three edges of the one internal face each join a new face
//     t0 to the face s_i beyond c's external face there: "attach s0, s1, s2 to t0";
//   - two external faces (Figs. 6, 9): the four edges with one external face join t0 or t1 to the
//     source beyond; the edge between the two internal faces joins t0 to t1 when c's fan about it
//     is closed (the seed's only case), else each to the end of its own run;
//   - one external face (Figs. 7, 8): the three edges of f0 attach s_i to t_i; the three other
//     edges attach t_i to t_j (again exactly when the fan about that edge is closed);
//   - no external face: the cell leaves a cavity whose four faces join each other or the surface;
//   - four external faces: an isolated cell just disappears.
// Cost: at most 4 new faces × 3 edges walks, each bounded by the tets about one edge.
//
// Reads: TetMesh (build). Writes: SimplexCells.
#include <array>
#include <cstdint>
#include <vector>

#include "components/simplices.hpp"
#include "engine/core/mesh_data.hpp"

namespace phaco::simplex {

inline constexpr double kLensDensityKgPerMm3 = 1.1e-6;  // crystalline lens ≈ 1100 kg/m³

// Cells of every tet of `mesh`, all alive, with internal connections and boundary links.
SimplexCells build_cells(const TetMesh& mesh, double density_kg_mm3 = kLensDensityKgPerMm3);

// Named by the number of external faces the cell had when removed.
enum class RemovalCase : uint8_t {
  Interior = 0,
  OneExternal = 1,
  TwoExternal = 2,
  ThreeExternal = 3,
  Isolated = 4
};

struct Removal {
  uint32_t cell = kNoSimplex;
  bool removed = false;  // false: the cell was already removed (nothing changed)
  RemovalCase kind = RemovalCase::Interior;
  uint8_t alive_neighbours = 0;  // neighbours before removal
  bool may_split = false;  // alive_neighbours ≥ 2 (systems/simplex confirm_split may clear it)
  std::array<uint32_t, 4> neighbours{kNoSimplex, kNoSimplex, kNoSimplex,
                                     kNoSimplex};  // across face k
  std::array<uint32_t, 4> new_faces{kNoSimplex, kNoSimplex, kNoSimplex,
                                    kNoSimplex};  // their new external face ids
};

// Removes one cell and updates internal connections and boundary links locally. Does not
// allocate or throw.
Removal remove_cell(SimplexCells& cells, uint32_t cell);

// A crack (issue 19, the chopper): the internal link between `cell` and its neighbour across
// `face` is broken, both faces become external and take their boundary links by the walk above,
// exactly as a removal's new faces do; the cells stay. Returns false when there was no link.
// Breaking links only ever splits, so fragments must be relabelled after (label_fragments_*).
// check_boundary rebuilds from the tets and does not know of cracks: it reports a cracked lens's
// broken links as neighbour mismatches. Does not allocate or throw.
bool break_link(SimplexCells& cells, uint32_t cell, uint32_t face);

// Partner of external face `face_id` across its edge slot `slot` by the walk through the solid;
// returns the partner face id and writes its edge slot, or kNoSimplex if the walk exceeds
// max_steps (a broken structure).
uint32_t walk_boundary_partner(const SimplexCells& cells, uint32_t face_id, uint32_t slot,
                               uint32_t* partner_slot, uint32_t max_steps = 4096);

// Number of external faces (alive cells' faces without a neighbour).
uint32_t count_external_faces(const SimplexCells& cells);

struct BoundaryCheck {
  uint32_t alive_cells = 0;
  uint32_t external_faces = 0;          // in the maintained structure
  uint32_t rebuilt_external_faces = 0;  // in the rebuild from the alive tets
  uint32_t neighbour_mismatches = 0;    // face slots whose neighbour differs from the rebuild
  uint32_t link_mismatches = 0;         // (face, edge) links that differ from the rebuild
  uint32_t asymmetric_links = 0;        // a → b across e but b does not point back across e
  uint32_t stale_entries = 0;           // links on internal faces / data on removed cells
  uint32_t alive_count_error = 0;       // |alive_count − alive cells|
  bool ok() const {
    return external_faces == rebuilt_external_faces && neighbour_mismatches == 0 &&
           link_mismatches == 0 && asymmetric_links == 0 && stale_entries == 0 &&
           alive_count_error == 0;
  }
};

// Rebuilds neighbours and boundary links from scratch from the alive cells' tets (construction
// loops 2 and 3 over the alive tets) and compares them with the incrementally maintained ones.
BoundaryCheck check_boundary(const SimplexCells& cells);

// Rebuilt boundary links only (construction loop 3 over the current neighbours): fills
// `links` (12 per cell, like SimplexCells::boundary_link). Exposed for timing the rebuild.
void rebuild_boundary_links(const SimplexCells& cells,
                            std::vector<std::array<uint32_t, 12>>& links);

}  // namespace phaco::simplex
