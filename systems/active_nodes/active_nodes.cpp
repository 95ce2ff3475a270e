#include "systems/active_nodes/active_nodes.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace phaco::active_nodes {

namespace {

double speed_sq(const Particles& p, uint32_t i) {
  return double(p.vx[i]) * p.vx[i] + double(p.vy[i]) * p.vy[i] + double(p.vz[i]) * p.vz[i];
}

// |net force|² on particle p: every spring of p (from the graph) plus the external load.
double net_force_sq(const SpringGraph& g, const WakeInputs& w, uint32_t p) {
  const Particles& x = *w.particles;
  const Springs& s = *w.springs;
  double fx = 0.0, fy = 0.0, fz = 0.0;
  if (w.external && p < w.external->fx.size())
    fx = w.external->fx[p], fy = w.external->fy[p], fz = w.external->fz[p];
  for (uint32_t k = g.begin(p); k < g.end(p); ++k) {
    const uint32_t q = g.neighbour[k], e = g.spring[k];
    const double dx = double(x.x[q]) - x.x[p], dy = double(x.y[q]) - x.y[p],
                 dz = double(x.z[q]) - x.z[p];
    const double l = std::sqrt(dx * dx + dy * dy + dz * dz);
    if (l <= 0.0) continue;
    const double ext = l - s.rest_length[e];
    const double mag =
        w.law == SpringLaw::Linear ? s.stiffness[e] * ext : s.stiffness[e] * ext * std::fabs(ext);
    fx += mag * dx / l, fy += mag * dy / l, fz += mag * dz / l;
  }
  return fx * fx + fy * fy + fz * fz;
}

}  // namespace

void clear_active_set(ActiveSet& set) {
  for (uint32_t p : set.particles) set.mark[p] = 0;
  set.particles.clear();
  set.springs.clear();
  set.fell_asleep.clear();
  set.woken = 0;
}

void update_active_set(const SpringGraph& graph, std::span<const uint32_t> seeds, uint32_t k_hops,
                       const WakeInputs& wake, ActiveSet& set) {
  const uint32_t n = graph.particle_count();
  if (set.mark.size() != n) {
    // First use, or a cut changed the particle count: the set starts afresh from the seeds (as it
    // always has after a topology change). The marks are cleared through the list that set them
    // and grow for the new particles (amortised, with room left at first use): no pass over the
    // body.
    for (uint32_t p : set.particles)
      if (p < set.mark.size()) set.mark[p] = 0;
    set.particles.clear();
    if (set.mark.capacity() < n) {
      set.mark.reserve(size_t{n} + n / 4 + 64);
      set.previous.reserve(size_t{n} + n / 4 + 64);
    }
    set.mark.resize(n, 0);
    set.previous.resize(n, 0);
  }
  // Last update's set becomes `previous`; marks are cleared through it.
  set.previous_list.assign(set.particles.begin(), set.particles.end());
  for (uint32_t p : set.previous_list) set.mark[p] = 0, set.previous[p] = 1;
  set.particles.clear();
  set.fell_asleep.clear();

  // Breadth-first k-hop ball around the seeds.
  set.queue.clear();
  set.hops.clear();
  for (uint32_t s : seeds) {
    if (s >= n || set.mark[s]) continue;
    set.mark[s] = 1;
    set.queue.push_back(s);
    set.hops.push_back(0);
  }
  for (size_t head = 0; head < set.queue.size(); ++head) {
    const uint32_t p = set.queue[head], h = set.hops[head];
    if (h >= k_hops) continue;
    for (uint32_t k = graph.begin(p); k < graph.end(p); ++k) {
      const uint32_t q = graph.neighbour[k];
      if (set.mark[q]) continue;
      set.mark[q] = 1;
      set.queue.push_back(q);
      set.hops.push_back(h + 1);
    }
  }
  set.particles.assign(set.queue.begin(), set.queue.end());
  const size_t ball = set.particles.size();

  // Wake rules, evaluated on the previous set and its sleeping frontier.
  const double motion_sq = wake.motion_threshold_mm * wake.motion_threshold_mm;
  const double load_sq = wake.force_threshold_mn * wake.force_threshold_mn;
  const bool force_rule = wake.particles && wake.springs;
  auto activate = [&](uint32_t q) {
    if (set.mark[q]) return;
    set.mark[q] = 1;
    set.particles.push_back(q);
  };
  for (uint32_t p : set.previous_list) {
    const bool moved =
        wake.particles && speed_sq(*wake.particles, p) * wake.dt_s * wake.dt_s > motion_sq;
    const bool loaded = force_rule && net_force_sq(graph, wake, p) > load_sq;
    if (moved || loaded) activate(p);
    for (uint32_t k = graph.begin(p); k < graph.end(p); ++k) {
      const uint32_t q = graph.neighbour[k];
      if (moved) {
        activate(q);
      } else if (force_rule && !set.previous[q] && !set.mark[q] &&
                 net_force_sq(graph, wake, q) > load_sq) {
        activate(q);  // sleeping frontier loaded by an active neighbour's springs
      }
    }
  }
  set.woken = static_cast<uint32_t>(set.particles.size() - ball);

  for (uint32_t p : set.previous_list) {
    if (!set.mark[p]) set.fell_asleep.push_back(p);
    set.previous[p] = 0;
  }
  std::sort(set.particles.begin(), set.particles.end());

  // Each spring once: from its lower active end, or from its only active end. Half the entries
  // to sort of listing it from both ends and removing the duplicates.
  set.spring_scratch.clear();
  for (uint32_t p : set.particles)
    for (uint32_t k = graph.begin(p); k < graph.end(p); ++k) {
      const uint32_t q = graph.neighbour[k];
      if (q > p || !set.mark[q]) set.spring_scratch.push_back(graph.spring[k]);
    }
  std::sort(set.spring_scratch.begin(), set.spring_scratch.end());
  const auto last = std::unique(set.spring_scratch.begin(), set.spring_scratch.end());
  set.springs.assign(set.spring_scratch.begin(), last);
}

}  // namespace phaco::active_nodes
