#pragma once
// Bookkeeping helpers of the membrane edits (membrane_edit.cpp), shared with the other edit files
// of systems/cut (vertex_insertion.cpp). Not for use outside this folder.
#include <cstdint>
#include <vector>

#include "systems/cut/membrane_edit.hpp"

namespace phaco::cut::detail {

// Edge slot k of triangle t (corners k, k+1) joining u and v in either direction; -1 if none.
int edge_slot(const Triangles& tr, uint32_t t, uint32_t u, uint32_t v);
// Sets t's link across edge (u, v) to n (nothing if t is kInvalidIndex).
void set_link(CutMesh& m, uint32_t t, uint32_t u, uint32_t v, uint32_t n);
// t's neighbour across edge (u, v), or kInvalidIndex.
uint32_t link_across(const CutMesh& m, uint32_t t, uint32_t u, uint32_t v);
// Adds the spring of edge (a, b) unless it exists (stiffness and rest length set on refresh).
void add_spring(CutMesh& m, uint32_t a, uint32_t b);
// Removes the spring of edge (a, b) if there is one.
void remove_spring(CutMesh& m, uint32_t a, uint32_t b);
void push_unique(std::vector<uint32_t>& v, uint32_t x);

}  // namespace phaco::cut::detail
