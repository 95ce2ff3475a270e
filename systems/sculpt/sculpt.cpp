#include "systems/sculpt/sculpt.hpp"

#include <algorithm>
#include <cassert>

#include "engine/core/invariants.hpp"

namespace phaco::sculpt {

double sculpt_radius_mm(double pedal, double power, double tip_radius_mm) {
  if (!(pedal >= 3.0)) return 0.0;
  const double p = std::clamp(power, 0.0, 1.0);
  return tip_radius_mm * (0.5 + 0.5 * p);
}

SculptState make_sculpt_state(const TetTopology& topo, const SculptOptions& options) {
  SculptState state;
  state.options = options;
  if (options.broadphase == Broadphase::Octree)
    state.octree = build_tet_octree(topo, options.octree_leaf_capacity);
  else
    state.dbvt.build(topo);
  state.visit_stamp.assign(topo.tet_count, 0);
  for (auto* v : {&state.removed, &state.seeds, &state.queue, &state.candidates, &state.tree_queue})
    v->reserve(1024);
  return state;
}

namespace {

// A fresh visit mark; clears the marks when the counter wraps so an old mark cannot collide.
void next_stamp(SculptState& s) {
  if (++s.stamp == 0) {
    std::fill(s.visit_stamp.begin(), s.visit_stamp.end(), 0u);
    s.stamp = 1;
  }
}

// Queues t unless already seen this step.
inline void enqueue(SculptState& s, uint32_t t) {
  if (s.visit_stamp[t] == s.stamp) return;
  s.visit_stamp[t] = s.stamp;
  s.queue.push_back(t);
}

// Seeds from the last removals: true when at least one of them meets the tip.
bool seed_from_last(const TetTopology& topo, std::span<const Vec3> positions, SculptState& s,
                    const TipCapsule& tip) {
  bool met = false;
  // Most recent removals last: they lie nearest the tip.
  for (auto it = s.seeds.rbegin(); it != s.seeds.rend(); ++it) {
    const uint32_t t = *it;
    if (!bound_touches_tip(topo, t, tip)) continue;
    enqueue(s, t);
    met = met || centre_in_tip(topo, t, tip);
  }
  if (met || s.queue.empty()) return met;
  for (auto it = s.queue.rbegin(); it != s.queue.rend(); ++it)
    if (tet_touches_tip(positions, topo.vertices[*it], tip, Narrowphase::ExactGjk)) return true;
  return false;
}

// The topology's per-tet columns in step with its count, and every tet's corners among the
// positions it is sculpted against (a lens whose vertices were rebuilt without its topology).
[[maybe_unused]] bool topology_fits(const TetTopology& topo, size_t vertex_count) {
  if (topo.vertices.size() != topo.tet_count ||
      !same_size(topo.vertices, topo.neighbours, topo.alive, topo.centre_x, topo.centre_y,
                 topo.centre_z, topo.bound_radius, topo.volume, topo.surface_slot)) {
    return false;
  }
  for (const std::array<uint32_t, 4>& tet : topo.vertices) {
    if (!all_below(tet, vertex_count)) return false;
  }
  return true;
}

}  // namespace

std::span<const uint32_t> sculpt_step(TetTopology& topo, std::span<const Vec3> positions,
                                      SculptState& s, const SculptTip& tip_in) {
  assert(topology_fits(topo, positions.size()));
  s.removed.clear();
  s.queue.clear();
  s.stats = SculptStats{};
  if (!(tip_in.radius_mm > 0.0) || topo.alive_count == 0) return {};
  const TipCapsule tip{tip_in.previous_centre, tip_in.centre, tip_in.radius_mm};
  next_stamp(s);

  const bool continued = s.options.continue_from_last && seed_from_last(topo, positions, s, tip);
  if (!continued) {
    s.queue.clear();
    next_stamp(s);  // forget the seeds looked at above
    s.stats.used_broadphase = true;
    s.candidates.clear();
    if (s.options.broadphase == Broadphase::Octree)
      octree_candidates(s.octree, topo, tip, s.tree_queue, s.candidates, s.stats.broadphase);
    else
      s.dbvt.candidates(topo, tip, s.candidates, s.stats.broadphase);
    std::sort(s.candidates.begin(), s.candidates.end());
    s.stats.candidates = static_cast<uint32_t>(s.candidates.size());
    for (uint32_t t : s.candidates) enqueue(s, t);
  }
  s.stats.seeds = static_cast<uint32_t>(s.queue.size());

  for (size_t head = 0; head < s.queue.size(); ++head) {
    const uint32_t t = s.queue[head];
    ++s.stats.walk_visits;
    if (topo.alive[t]) {
      ++s.stats.narrowphase_tests;
      if (narrowphase_hit(topo, positions, t, tip, s.options.narrowphase)) {
        remove_tet(topo, t);
        if (s.options.broadphase == Broadphase::Dbvt) s.dbvt.remove(t);
        s.removed.push_back(t);
      }
    }
    for (uint32_t n : topo.neighbours[t]) {
      if (n == kNoTet || s.visit_stamp[n] == s.stamp) continue;
      s.visit_stamp[n] = s.stamp;  // looked at once per step, queued or not
      ++s.stats.neighbour_tests;
      if (bound_touches_tip(topo, n, tip)) s.queue.push_back(n);
    }
  }
  s.stats.removed = static_cast<uint32_t>(s.removed.size());
  if (!s.removed.empty()) s.seeds.assign(s.removed.begin(), s.removed.end());
  return s.removed;
}

void surface_triangles(const TetTopology& topo, std::vector<std::array<uint32_t, 3>>& out) {
  out.clear();
  for (uint32_t t : topo.surface) {
    const auto& v = topo.vertices[t];
    for (int k = 0; k < 4; ++k) {
      const uint32_t n = topo.neighbours[t][k];
      if (n != kNoTet && topo.alive[n]) continue;
      out.push_back({v[kTetFaceCorners[k][0]], v[kTetFaceCorners[k][1]], v[kTetFaceCorners[k][2]]});
    }
  }
}

}  // namespace phaco::sculpt
