#include "systems/cut/spring_order.hpp"

#include <algorithm>
#include <numeric>
#include <vector>

namespace phaco::cut {

void compact_and_sort_springs(CutMesh& m) {
  Springs& s = m.springs;
  table_compact(s);
  const uint32_t n = s.slots.size();
  std::vector<uint32_t> order(n);
  std::iota(order.begin(), order.end(), 0u);
  std::sort(order.begin(), order.end(), [&](uint32_t a, uint32_t b) {
    return s.i[a] != s.i[b] ? s.i[a] < s.i[b] : s.j[a] < s.j[b];
  });
  const auto permute = [&](auto& col) {
    auto copy = col;
    for (uint32_t k = 0; k < n; ++k) col[k] = copy[order[k]];
  };
  permute(s.i), permute(s.j), permute(s.rest_length), permute(s.stiffness);
  m.topology.added_springs.clear();  // indices changed: the physics is rebuilt from the table
  m.topology.removed_springs.clear();
  m.topology.spring_of_edge.clear();
  for (uint32_t k = 0; k < n; ++k) m.topology.spring_of_edge.emplace(edge_key(s.i[k], s.j[k]), k);
}

}  // namespace phaco::cut
