#pragma once
// After cuts, the spring table has holes and new springs at its end; the force pass wants it
// dense and sorted by (i, j) (components/springs.hpp: SpringBlocks). This closes the holes, sorts
// the springs and rebuilds the cut's spring index to match — a pass over all springs
// (O(S log S)), run once after a frame's topology changes, not per edit.
//
// Reads and writes: <body>.springs, the MembraneTopology's spring index.
#include "systems/cut/membrane_edit.hpp"

namespace phaco::cut {

void compact_and_sort_springs(CutMesh& mesh);

}  // namespace phaco::cut
