#include "engine/schedule/frame_graph.hpp"

#include <algorithm>
#include <stdexcept>
#include <unordered_map>

namespace phaco {
namespace {

std::string quote_name(std::string_view name) {
  std::string q(1, '\'');  // built by appends: GCC 12 warns falsely on "'" + std::string
  q += name;
  q += '\'';
  return q;
}

[[noreturn]] void reject(const std::string& what) {
  throw std::invalid_argument("FrameGraph: " + what);
}

void check_descriptions(const std::vector<SystemDesc>& systems) {
  std::unordered_map<std::string_view, size_t> seen;
  for (size_t i = 0; i < systems.size(); ++i) {
    const SystemDesc& s = systems[i];
    if (s.name.empty()) {
      reject("system #" + std::to_string(i) + " (in registration order) has an empty name");
    }
    if (!s.run) reject("system " + quote_name(s.name) + " has no run function");
    if (!seen.emplace(s.name, i).second) {
      reject("two systems are named " + quote_name(s.name) + "; system names must be unique");
    }
    for (const auto* list : {&s.reads, &s.writes}) {
      for (const std::string& c : *list) {
        if (c.empty()) {
          reject("system " + quote_name(s.name) + " lists an empty component name in its " +
                 (list == &s.reads ? "reads" : "writes"));
        }
      }
    }
  }
  for (const SystemDesc& s : systems) {
    for (const std::string& a : s.after) {
      if (!seen.contains(a)) {
        reject("system " + quote_name(s.name) + " runs after " + quote_name(a) +
               ", but no system has that name");
      }
    }
  }
}

// Sorted-id intersection appended to `out`.
void intersect(const std::vector<uint32_t>& a, const std::vector<uint32_t>& b,
               std::vector<uint32_t>& out) {
  std::set_intersection(a.begin(), a.end(), b.begin(), b.end(), std::back_inserter(out));
}

std::string dot_escape(std::string_view text) {
  std::string out;
  for (char c : text) {
    if (c == '"' || c == '\\') out.push_back('\\');
    out.push_back(c);
  }
  return out;
}

}  // namespace

FrameGraph::FrameGraph(std::vector<SystemDesc> systems) : systems_(std::move(systems)) {
  check_descriptions(systems_);
  std::stable_sort(systems_.begin(), systems_.end(),
                   [](const SystemDesc& a, const SystemDesc& b) { return a.phase < b.phase; });
  const size_t n = systems_.size();

  // Intern component names so the pairwise pass compares sorted integer lists.
  std::unordered_map<std::string, uint32_t> component_id;
  auto intern = [&](const std::vector<std::string>& names) {
    std::vector<uint32_t> ids;
    for (const std::string& c : names) {
      auto [it, added] = component_id.emplace(c, static_cast<uint32_t>(components_.size()));
      if (added) components_.push_back(c);
      ids.push_back(it->second);
    }
    std::sort(ids.begin(), ids.end());
    ids.erase(std::unique(ids.begin(), ids.end()), ids.end());
    return ids;
  };
  for (const SystemDesc& s : systems_) {
    read_ids_.push_back(intern(s.reads));
    write_ids_.push_back(intern(s.writes));
  }

  // Every edge with its reasons, before reduction. Edge (p, s) lives in out[p].
  struct Edge {
    uint32_t to;
    std::string reason;
  };
  std::vector<std::vector<Edge>> out(n);
  auto add_edge = [&](size_t p, size_t s, std::string_view reason) {
    for (Edge& e : out[p]) {
      if (e.to == s) {
        e.reason += ", ";
        e.reason += reason;
        return;
      }
    }
    out[p].push_back({static_cast<uint32_t>(s), std::string(reason)});
  };

  std::vector<uint32_t> shared;
  for (size_t s = 0; s < n; ++s) {
    for (size_t p = 0; p < s; ++p) {
      shared.clear();
      intersect(write_ids_[p], read_ids_[s], shared);
      intersect(write_ids_[p], write_ids_[s], shared);
      intersect(read_ids_[p], write_ids_[s], shared);
      if (systems_[p].barrier || systems_[s].barrier) add_edge(p, s, "barrier");
      if (shared.empty()) continue;
      std::sort(shared.begin(), shared.end());
      shared.erase(std::unique(shared.begin(), shared.end()), shared.end());
      std::string reason;
      for (uint32_t c : shared) {
        if (!reason.empty()) reason += ", ";
        reason += components_[c];
      }
      add_edge(p, s, reason);
    }
  }
  for (size_t s = 0; s < n; ++s) {
    for (const std::string& name : systems_[s].after) {
      const size_t p = find(name);
      if (p == s) reject("cycle: " + name + " -> " + name + " (a system lists itself in 'after')");
      add_edge(p, s, "after");
    }
  }

  // Kahn's algorithm; what is left over lies on or behind a cycle.
  std::vector<uint32_t> in_degree(n, 0);
  for (const auto& edges : out) {
    for (const Edge& e : edges) ++in_degree[e.to];
  }
  std::vector<uint32_t> topo;
  topo.reserve(n);
  for (size_t i = 0; i < n; ++i) {
    if (in_degree[i] == 0) topo.push_back(static_cast<uint32_t>(i));
  }
  for (size_t head = 0; head < topo.size(); ++head) {
    for (const Edge& e : out[topo[head]]) {
      if (--in_degree[e.to] == 0) topo.push_back(e.to);
    }
  }
  if (topo.size() != n) {
    // Every left-over node has a left-over predecessor: walk backwards until a node repeats.
    std::vector<std::vector<uint32_t>> preds(n);
    for (size_t p = 0; p < n; ++p) {
      for (const Edge& e : out[p]) {
        if (in_degree[p] > 0 && in_degree[e.to] > 0)
          preds[e.to].push_back(static_cast<uint32_t>(p));
      }
    }
    size_t v = 0;
    while (in_degree[v] == 0) ++v;
    std::vector<size_t> walk;
    std::vector<size_t> position(n, n);
    while (position[v] == n) {
      position[v] = walk.size();
      walk.push_back(v);
      v = *std::min_element(preds[v].begin(), preds[v].end());
    }
    // walk[position[v]..] is the cycle in backward order.
    std::string path = systems_[v].name;
    for (size_t k = walk.size(); k-- > position[v];) path += " -> " + systems_[walk[k]].name;
    reject("the ordering has a cycle: " + path +
           " (edges come from shared components, phases, barriers and 'after' lists; an 'after' "
           "naming a system of a later phase is the usual cause)");
  }

  // Transitive closure, filled in reverse topological order.
  closure_words_ = (n + 63) / 64;
  closure_.assign(n * closure_words_, 0);
  for (size_t k = n; k-- > 0;) {
    const size_t a = topo[k];
    uint64_t* row = &closure_[a * closure_words_];
    for (const Edge& e : out[a]) {
      row[e.to / 64] |= uint64_t{1} << (e.to % 64);
      const uint64_t* sub = &closure_[e.to * closure_words_];
      for (size_t w = 0; w < closure_words_; ++w) row[w] |= sub[w];
    }
  }

  // Transitive reduction: drop p -> s when another successor of p already reaches s.
  successors_.assign(n, {});
  edge_reasons_.assign(n, {});
  predecessor_counts_.assign(n, 0);
  for (size_t p = 0; p < n; ++p) {
    std::sort(out[p].begin(), out[p].end(),
              [](const Edge& a, const Edge& b) { return a.to < b.to; });
    for (const Edge& e : out[p]) {
      const bool implied = std::any_of(out[p].begin(), out[p].end(), [&](const Edge& other) {
        return other.to != e.to && reaches(other.to, e.to);
      });
      if (implied) continue;
      successors_[p].push_back(e.to);
      edge_reasons_[p].push_back(e.reason);
      ++predecessor_counts_[e.to];
    }
  }
}

size_t FrameGraph::find(std::string_view name) const {
  for (size_t i = 0; i < systems_.size(); ++i) {
    if (systems_[i].name == name) return i;
  }
  return systems_.size();
}

bool FrameGraph::reaches(size_t a, size_t b) const {
  return (closure_[a * closure_words_ + b / 64] >> (b % 64)) & 1u;
}

std::vector<std::pair<size_t, size_t>> FrameGraph::write_conflicts() const {
  return find_write_conflicts(systems_, [this](size_t a, size_t b) { return reaches(a, b); });
}

std::vector<std::pair<size_t, size_t>> find_write_conflicts(
    const std::vector<SystemDesc>& systems, const std::function<bool(size_t, size_t)>& reaches) {
  std::vector<std::pair<size_t, size_t>> conflicts;
  for (size_t i = 0; i < systems.size(); ++i) {
    for (size_t j = i + 1; j < systems.size(); ++j) {
      const auto& wi = systems[i].writes;
      const auto& wj = systems[j].writes;
      const bool share = std::any_of(wi.begin(), wi.end(), [&](const std::string& c) {
        return std::find(wj.begin(), wj.end(), c) != wj.end();
      });
      if (share && !reaches(i, j) && !reaches(j, i)) conflicts.emplace_back(i, j);
    }
  }
  return conflicts;
}

std::string FrameGraph::to_dot() const {
  std::string dot = "digraph frame {\n  rankdir=LR;\n  node [shape=box, fontname=\"Helvetica\"];\n";
  for (int ph = 0; ph < kPhaseCount; ++ph) {
    const Phase phase = static_cast<Phase>(ph);
    bool opened = false;
    for (const SystemDesc& s : systems_) {
      if (s.phase != phase) continue;
      if (!opened) {
        dot += "  subgraph cluster_" + std::string(to_string(phase)) + " {\n    label=\"" +
               std::string(to_string(phase)) + "\";\n";
        opened = true;
      }
      const std::string name = dot_escape(s.name);
      dot += "    \"" + name + "\" [label=\"" + name + "\\n(" + std::string(to_string(phase)) +
             (s.barrier ? ", barrier)\", style=filled, fillcolor=lightgrey];\n" : ")\"];\n");
    }
    if (opened) dot += "  }\n";
  }
  for (size_t p = 0; p < successors_.size(); ++p) {
    for (size_t k = 0; k < successors_[p].size(); ++k) {
      dot += "  \"" + dot_escape(systems_[p].name) + "\" -> \"" +
             dot_escape(systems_[successors_[p][k]].name) + "\" [label=\"" +
             dot_escape(edge_reasons_[p][k]) + "\"];\n";
    }
  }
  dot += "}\n";
  return dot;
}

}  // namespace phaco
