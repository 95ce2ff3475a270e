#pragma once
// The per-frame task graph, derived once per scene from the systems' declared access.
//
//   "earlier" = stable sort by phase, registration order within a phase.
//   P -> S  when P is earlier than S and
//             P writes what S reads or writes   (read-after-write, write-after-write)
//          or P reads  what S writes            (write-after-read)
//           or S lists P in `after`             (may point backwards: cycles are rejected)
//           or P or S is a barrier              (everything earlier -> barrier -> everything later)
//
// Readers of the same component get no edge, so they may run concurrently. Because every pair of
// writers of one component is ordered, any two systems that the executor may run at the same time
// touch disjoint data; that is what makes a 1-thread and an N-thread frame produce the same state.
// The stored successor lists are transitively reduced (fewer edges to count down each frame);
// reaches() answers for the full closure.
#include <cstddef>
#include <cstdint>
#include <functional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "engine/schedule/system.hpp"

namespace phaco {

class FrameGraph {
 public:
  // Throws std::invalid_argument naming the systems involved: empty or duplicate name, missing run
  // function, empty component name, `after` naming an unknown system, or a cycle ("a -> b -> a").
  explicit FrameGraph(std::vector<SystemDesc> systems);

  size_t size() const { return systems_.size(); }
  const SystemDesc& system(size_t i) const { return systems_[i]; }  // in sorted order
  // Index of the system called `name`, or size() if there is none.
  size_t find(std::string_view name) const;

  // Direct dependencies after transitive reduction: successors()[p] lists every s with edge p -> s.
  const std::vector<std::vector<uint32_t>>& successors() const { return successors_; }
  // Why each edge exists, parallel to successors(): component names, "after", "barrier".
  const std::vector<std::vector<std::string>>& edge_reasons() const { return edge_reasons_; }
  // Number of direct predecessors of each system (after reduction).
  const std::vector<uint32_t>& predecessor_counts() const { return predecessor_counts_; }

  bool reaches(size_t a, size_t b) const;  // a path a -> ... -> b exists (a != b)
  bool ordered(size_t a, size_t b) const { return reaches(a, b) || reaches(b, a); }

  // Unordered pairs (i < j) that write a common component; empty for every graph this class builds.
  std::vector<std::pair<size_t, size_t>> write_conflicts() const;

  // Interned component names; read_ids(i) / write_ids(i) are sorted, unique ids into components().
  const std::vector<std::string>& components() const { return components_; }
  const std::vector<uint32_t>& read_ids(size_t i) const { return read_ids_[i]; }
  const std::vector<uint32_t>& write_ids(size_t i) const { return write_ids_[i]; }

  // GraphViz DOT: one cluster per phase, one node per system, one labelled edge per dependency.
  std::string to_dot() const;

 private:
  std::vector<SystemDesc> systems_;
  std::vector<std::string> components_;
  std::vector<std::vector<uint32_t>> read_ids_;
  std::vector<std::vector<uint32_t>> write_ids_;
  std::vector<std::vector<uint32_t>> successors_;
  std::vector<std::vector<std::string>> edge_reasons_;
  std::vector<uint32_t> predecessor_counts_;
  std::vector<uint64_t> closure_;  // row-major bit matrix, closure_words_ words per row
  size_t closure_words_ = 0;
};

// The detector behind write_conflicts(), usable on any hand-made ordering: every pair i < j whose
// write lists share a component name while neither reaches(i, j) nor reaches(j, i).
std::vector<std::pair<size_t, size_t>> find_write_conflicts(
    const std::vector<SystemDesc>& systems, const std::function<bool(size_t, size_t)>& reaches);

}  // namespace phaco
