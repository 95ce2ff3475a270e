#pragma once
// Fragments of the lens (issue 5 item 5, seed 002 §6): connected components of the alive simplex
// cells over their internal links. Each component is a fragment with its own rest shape.
//
// Two labellings that give the SAME table (components/fragments.hpp: fragments numbered by their
// smallest cell id, members ascending):
//   - painting: the seed's "recursive painting algorithm", iterative with an explicit stack;
//     cells are visited in id order, so a fragment's label is the order of its first cell;
//   - union-find, parallel: unions over internal links in parallel (lock-free: a root is linked
//     below the smaller root by compare-exchange on 32-bit parents, so every root is its set's
//     smallest id whatever the interleaving), then labels = roots renumbered in id order by
//     per-chunk counts and a prefix over fixed chunks. Same result for any thread count.
// Mass and rest centroid of each fragment are summed over its members in ascending order
// (double), so every path gives bit-identical fragments.
//
// After removals (update_fragments) the labelling is redone only when a removal could split a
// fragment: a removed cell with at least two alive neighbours (Removal::alive_neighbours) that a
// bounded local search did not join up again. The search (confirm_split, run right after each
// remove_cell, before the next) walks from one alive neighbour over alive cells until it has met
// all the others or spent its budget; on the lens most surface removals have two or three
// neighbours that meet again within a few cells about the shared edges, so the relabel becomes
// rare. Otherwise removed cells just leave their fragments in place (an emptied fragment
// disappears) and the numbering by smallest cell id is restored. When a removal could split a
// fragment, only the fragments holding such removals are relabelled (a flood over their own
// members: a fragment's cells link to its cells only), the others keep their members and masses,
// and all are renumbered by smallest cell id: the same table as a labelling of every cell (the
// lens at level 3: 52k cells, 7 ms of the frame per split on 2 threads when every cell was
// relabelled).
//
// Reads: SimplexCells (alive, neighbour, mass, rest centres). Writes: Fragments.
#include <array>
#include <cstdint>
#include <span>
#include <vector>

#include "components/fragments.hpp"
#include "components/simplices.hpp"
#include "systems/simplex/simplex_cells.hpp"

namespace phaco::simplex {

struct FragmentScratch {
  std::vector<uint32_t> stack;  // painting, local search
  std::vector<uint32_t> stamp;  // local search: visit stamp per cell
  uint32_t stamp_now = 0;
  std::vector<uint32_t> parent;       // union-find
  std::vector<uint32_t> chunk_roots;  // union-find renumbering
  std::vector<uint32_t> old_to_new;   // update_fragments
  std::vector<uint8_t> touched;       // update_fragments: 1 had a removal, 2 may have split
  // update_fragments after a possible split: the pieces (a fragment kept in place, `source`, its
  // members in Fragments::members; or a new list in piece_members), the new table before the swap.
  struct Piece {
    uint32_t first, source, begin, end;  // smallest cell; old fragment or kNoSimplex; range
    std::array<double, 4> mass;          // mass and rest centroid
  };
  std::vector<Piece> pieces;
  std::vector<uint32_t> piece_members, table_members, table_offsets;
};

// Right after remove_cell(cells, r.cell): clears r.may_split when the removed cell's alive
// neighbours still meet each other through at most `budget` alive cells. Deterministic.
void confirm_split(const SimplexCells& cells, Removal& r, FragmentScratch& scratch,
                   uint32_t budget = 256);

void label_fragments_painting(const SimplexCells& cells, Fragments& out, FragmentScratch& scratch);

// grain: cells per chunk of the parallel passes.
void label_fragments_union_find(const SimplexCells& cells, Fragments& out, FragmentScratch& scratch,
                                uint32_t grain = 4096);

struct FragmentUpdate {
  bool relabelled = false;  // a removal could split: labelled again (union-find, in parallel)
  uint32_t fragments = 0;   // fragments after the update
};

// Brings `frags` (valid for the cells before `removals`) up to date after those removals.
FragmentUpdate update_fragments(const SimplexCells& cells, std::span<const Removal> removals,
                                Fragments& frags, FragmentScratch& scratch);

}  // namespace phaco::simplex
