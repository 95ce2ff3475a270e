#pragma once
// Fragments of the lens: the connected components of the alive simplex cells over their internal
// links (seed 002 §6, "recognized by a recursive painting algorithm"). Each fragment is a rigid
// body for shape matching with its own rest shape: the rest centres of its member cells
// (SimplexCells::rest_x/y/z) about its rest centroid.
//
// Labels are normalised: fragments are numbered in the order of their smallest cell id, and
// members are listed in ascending cell id, so any labelling method gives the same table.
#include <cstdint>
#include <vector>

namespace phaco {

struct Fragments {
  std::vector<uint32_t> label;  // per cell: fragment id, kNoSimplex for a removed cell
  std::vector<uint32_t>
      offsets;  // CSR, count + 1 entries: members of f are [offsets[f], offsets[f+1])
  std::vector<uint32_t> members;                  // cell ids, ascending within each fragment
  std::vector<double> mass;                       // per fragment, kg
  std::vector<double> rest_cx, rest_cy, rest_cz;  // mass-weighted rest centroid, mm
  uint32_t count = 0;

  uint32_t size_of(uint32_t f) const { return offsets[f + 1] - offsets[f]; }
};

}  // namespace phaco
