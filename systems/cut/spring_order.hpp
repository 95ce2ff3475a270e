#pragma once
// After cuts, the spring table has tombstones and new springs at its end (the blocks' unplanned
// tail, components/springs.hpp). This closes the holes, sorts the springs by (i, j) and rebuilds
// the cut's spring index to match — a pass over all springs (O(S log S)). The scene runs it
// rarely (when tail and tombstones reach a fraction of the table) and only in a frame without a
// topology change (procedures/scene/capsule_cutting.hpp); it clears the index's change lists.
//
// Reads and writes: <body>.springs, the MembraneTopology's spring index.
#include "systems/cut/membrane_edit.hpp"

namespace phaco::cut {

void compact_and_sort_springs(CutMesh& mesh);

}  // namespace phaco::cut
