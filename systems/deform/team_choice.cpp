#include "systems/deform/team_choice.hpp"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>

namespace phaco::deform {

namespace {

// Size classes by powers of two: the team's cost per node falls as the set grows (fewer
// handoffs per node), so a set of 300 nodes and one of 3,000 need not agree.
TeamChoice::SizeClass& size_class(TeamChoice& choice, uint32_t nodes) {
  const int log2 = std::bit_width(nodes) - 1;
  const size_t k = size_t(std::clamp(log2 - 8, 0, int(choice.classes.size()) - 1));
  return choice.classes[k];
}

}  // namespace

double TeamChoice::Recent::least() const {
  const size_t n = std::min<size_t>(steps, ns.size());
  return n == 0 ? 0.0 : *std::min_element(ns.begin(), ns.begin() + std::ptrdiff_t(n));
}

bool choose_team(TeamChoice& choice, uint32_t nodes, const TeamChoiceRule& rule) {
  if (nodes < rule.min_nodes) return false;
  TeamChoice::SizeClass& c = size_class(choice, nodes);
  // Trials first, alternating, so both costs come from the same stretch of the run.
  if (c.alone.steps < rule.trial_steps || c.team.steps < rule.trial_steps)
    return c.team.steps < c.alone.steps;
  const bool team_cheaper = c.team.least() < c.alone.least();
  // A turned choice: the costs moved (the host moved the vCPUs), so look again soon.
  if (c.retrial_interval == 0 || team_cheaper != c.team_was_cheaper) {
    c.retrial_interval = rule.retrial_every;
    c.since_trial = 0;
  }
  c.team_was_cheaper = team_cheaper;
  // Now and then the costlier way: the host may have moved the cores (team_choice.hpp), and a
  // cost last measured minutes ago says nothing of now. While retrials keep confirming the
  // choice, they thin out (TeamChoiceRule).
  if (++c.since_trial >= c.retrial_interval) {
    c.since_trial = 0;
    c.retrial_interval =
        std::min(2 * c.retrial_interval, std::max(rule.retrial_most, rule.retrial_every));
    return !team_cheaper;
  }
  return team_cheaper;
}

void record_team_step(TeamChoice& choice, uint32_t nodes, bool on_team, double ns_per_node_it,
                      const TeamChoiceRule& rule) {
  if (nodes < rule.min_nodes || !std::isfinite(ns_per_node_it) || ns_per_node_it < 0) return;
  TeamChoice::Recent& r =
      on_team ? size_class(choice, nodes).team : size_class(choice, nodes).alone;
  r.ns[r.next] = ns_per_node_it;
  r.next = uint32_t((r.next + 1) % r.ns.size());
  if (r.steps < UINT32_MAX) ++r.steps;
}

}  // namespace phaco::deform
