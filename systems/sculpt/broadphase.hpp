#pragma once
// Broadphases of the sculpting step: which alive tets may touch the tip (seed 000 §5.3).
//
// Both return the same candidate set, sorted by tet index: alive tets whose bounding sphere
// (centre, bound_radius) touches the tip capsule. Both are built once; a removed tet is skipped by
// its alive flag (octree) or deleted from the tree (btDbvt::remove), never rebuilt.
//
//  - Octree (the seed's): tets go to the octant holding their centre, down to leaves of at most
//    `leaf_capacity` tets; a node's box bounds its tets' bounding spheres. Each leaf's list is
//    depth-sorted toward the viewer (+z, the surgeon, first), so a leaf scan starts at the front
//    and stops at the first tet below the tip's z window ("tetrahedrons closer to the user's
//    viewpoint are placed at the front of the list to expedite tetrahedron search"). Descent is
//    breadth-first from the root, as in the seed.
//  - Dbvt: Bullet's dynamic AABB tree over the same spheres' boxes, queried by collideTV with the
//    capsule's box (no-stack-allocation variant, the stack kept between queries).
// Reads tet centres, bound radii, alive flags. Writes only its own tree (Dbvt removal).
#include <cstdint>
#include <memory>
#include <span>
#include <vector>

#include "components/tet_topology.hpp"
#include "systems/sculpt/tip_contact.hpp"

namespace phaco::sculpt {

enum class Broadphase { Octree, Dbvt };
const char* to_string(Broadphase broadphase);

struct BroadphaseStats {
  uint32_t nodes_visited = 0;  // octree nodes whose box was tested (btDbvt does not report it)
  uint32_t tets_scanned = 0;   // leaf entries looked at
};

struct OctreeNode {
  float lo[3], hi[3];   // mm, bounds of the subtree's tet bounding spheres
  uint32_t first = 0;   // internal: first child node; leaf: first entry in TetOctree::items
  uint32_t count = 0;   // internal: child count (children contiguous); leaf: entry count
  float max_bound = 0;  // leaf: largest tet bound_radius among its entries, mm
  bool leaf = false;
};

struct TetOctree {
  std::vector<OctreeNode> nodes;  // nodes[0] is the root
  std::vector<uint32_t> items;    // tet ids, leaf by leaf, each leaf by centre z descending
  std::vector<float> item_z;      // mm, centre z of items[i]
  uint32_t leaf_capacity = 0;
  uint32_t depth = 0;  // deepest level reached (root = 0)
};

TetOctree build_tet_octree(const TetTopology& topo, uint32_t leaf_capacity);

// Appends the candidates to `out` (unsorted, each once); `queue` is breadth-first scratch.
void octree_candidates(const TetOctree& tree, const TetTopology& topo, const TipCapsule& tip,
                       std::vector<uint32_t>& queue, std::vector<uint32_t>& out,
                       BroadphaseStats& stats);

// Bullet btDbvt over the tets (Bullet stays out of this header).
class TetDbvt {
 public:
  TetDbvt();
  ~TetDbvt();
  TetDbvt(TetDbvt&&) noexcept;
  TetDbvt& operator=(TetDbvt&&) noexcept;

  void build(const TetTopology& topo);
  bool built() const { return impl_ != nullptr; }
  void remove(uint32_t tet);
  // Appends the candidates to `out` (unsorted, each once).
  void candidates(const TetTopology& topo, const TipCapsule& tip, std::vector<uint32_t>& out,
                  BroadphaseStats& stats) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace phaco::sculpt
