#include "systems/force_propagation/force_propagation.hpp"

#include <Eigen/Cholesky>
#include <Eigen/Core>
#include <algorithm>
#include <cmath>

namespace phaco::force_propagation {

namespace {

struct NodeState {
  Eigen::Vector3d force;  // net force on the node, mN
  Eigen::Matrix3d k;      // 3×3 stiffness block, mN/mm
};

// Net spring force on node i and its stiffness block, from the current positions.
NodeState node_state(const Particles& p, const Springs& s, SpringLaw law, const SpringGraph& g,
                     uint32_t i) {
  NodeState st{Eigen::Vector3d::Zero(), Eigen::Matrix3d::Zero()};
  const Eigen::Vector3d xi(p.x[i], p.y[i], p.z[i]);
  for (uint32_t r = g.begin(i); r < g.end(i); ++r) {
    const uint32_t j = g.neighbour[r], e = g.spring[r];
    const Eigen::Vector3d d = Eigen::Vector3d(p.x[j], p.y[j], p.z[j]) - xi;
    const double l = d.norm();
    if (l <= 0.0) continue;
    const Eigen::Vector3d n = d / l;
    const double ext = l - s.rest_length[e];
    const double k = s.stiffness[e];
    const double tension = law == SpringLaw::Linear ? k * ext : k * ext * std::fabs(ext);
    const double tangent = law == SpringLaw::Linear ? k : 2.0 * k * std::fabs(ext);
    st.force += tension * n;
    // A compressed spring would make the transverse term negative (it buckles); leaving it out
    // keeps the local step a descent step.
    const double transverse = std::max(tension, 0.0) / l;
    st.k += (tangent - transverse) * (n * n.transpose());
    st.k.diagonal().array() += transverse;
  }
  return st;
}

// One local Newton step at node i; returns the length of the move, mm.
double relax_node(Particles& p, const Springs& s, SpringLaw law, const SpringGraph& g, uint32_t i,
                  const Eigen::Vector3d& external, double omega) {
  NodeState st = node_state(p, s, law, g, i);
  st.force += external;
  const double trace = st.k.trace();
  if (!(trace > 0.0)) return 0.0;  // no stiffness at all: nothing to balance against
  st.k.diagonal().array() += 1e-9 * trace;
  const Eigen::Vector3d dx = omega * st.k.ldlt().solve(st.force);
  if (!dx.allFinite()) return 0.0;
  p.x[i] = static_cast<float>(p.x[i] + dx.x());
  p.y[i] = static_cast<float>(p.y[i] + dx.y());
  p.z[i] = static_cast<float>(p.z[i] + dx.z());
  return dx.norm();
}

// Appends layer `layer` (neighbours of layer − 1 not seen yet); false when it is empty.
bool expand_layer(const SpringGraph& g, PropagationScratch& sc, int layer) {
  const uint32_t from = sc.layer_begin[layer - 1], to = sc.layer_begin[layer];
  for (uint32_t o = from; o < to; ++o) {
    const uint32_t v = sc.order[o];
    for (uint32_t r = g.begin(v); r < g.end(v); ++r) {
      const uint32_t w = g.neighbour[r];
      if (sc.layer_of[w] >= 0) continue;
      sc.layer_of[w] = layer;
      sc.order.push_back(w);
    }
  }
  sc.layer_begin.push_back(static_cast<uint32_t>(sc.order.size()));
  return sc.layer_begin[layer + 1] > sc.layer_begin[layer];
}

}  // namespace

PropagationResult propagate(Particles& particles, const Springs& springs, SpringLaw law,
                            const SpringGraph& graph, std::span<const uint32_t> sources,
                            const PropagationSettings& settings, PropagationScratch& sc,
                            const SourceForces* forces) {
  PropagationResult result;
  const uint32_t n = graph.particle_count();
  if (sc.layer_of.size() != n) sc.layer_of.assign(n, -1);
  sc.order.clear();
  sc.layer_begin.assign(1, 0);
  sc.ext_x.clear(), sc.ext_y.clear(), sc.ext_z.clear();

  const bool with_forces = forces != nullptr && forces->fx.size() == sources.size() &&
                           forces->fy.size() == sources.size() &&
                           forces->fz.size() == sources.size();
  for (size_t s = 0; s < sources.size(); ++s) {
    const uint32_t v = sources[s];
    if (v >= n || sc.layer_of[v] >= 0) continue;
    sc.layer_of[v] = 0;
    sc.order.push_back(v);
    sc.ext_x.push_back(with_forces ? forces->fx[s] : 0.0f);
    sc.ext_y.push_back(with_forces ? forces->fy[s] : 0.0f);
    sc.ext_z.push_back(with_forces ? forces->fz[s] : 0.0f);
  }
  sc.layer_begin.push_back(static_cast<uint32_t>(sc.order.size()));

  const auto movable = [&](uint32_t v) { return particles.kind[v] == ParticleKind::Free; };
  const double tol = settings.tolerance_mm;
  int built = 0;  // layers 0..built are in `order`
  int front = 0;
  for (int sweep = 0; sweep < std::max(settings.sweeps, 1); ++sweep) {
    double sweep_move = 0.0;
    if (with_forces) {
      for (uint32_t o = sc.layer_begin[0]; o < sc.layer_begin[1]; ++o) {
        const uint32_t v = sc.order[o];
        if (!movable(v)) continue;
        sweep_move = std::max(
            sweep_move, relax_node(particles, springs, law, graph, v,
                                   {sc.ext_x[o], sc.ext_y[o], sc.ext_z[o]}, settings.relaxation));
        ++result.node_updates;
      }
    }
    for (int layer = 1; layer <= settings.max_layers; ++layer) {
      if (layer > built) {
        if (!expand_layer(graph, sc, layer)) break;
        built = layer;
      }
      double layer_move = 0.0;
      for (uint32_t o = sc.layer_begin[layer]; o < sc.layer_begin[layer + 1]; ++o) {
        const uint32_t v = sc.order[o];
        if (!movable(v)) continue;
        layer_move = std::max(layer_move, relax_node(particles, springs, law, graph, v,
                                                     Eigen::Vector3d::Zero(), settings.relaxation));
        ++result.node_updates;
      }
      sweep_move = std::max(sweep_move, layer_move);
      if (layer >= front) {
        front = layer;
        if (layer_move <= tol) break;
      }
    }
    result.sweeps_done = sweep + 1;
    result.last_sweep_move_mm = sweep_move;
    if (sweep_move <= tol) break;
  }

  result.layers_reached = front;
  result.nodes_touched = sc.layer_begin[front + 1];
  for (uint32_t o = 0; o < result.nodes_touched; ++o) {
    const uint32_t v = sc.order[o];
    if (!movable(v) || (o < sc.layer_begin[1] && !with_forces)) continue;
    NodeState st = node_state(particles, springs, law, graph, v);
    if (o < sc.layer_begin[1]) st.force += Eigen::Vector3d(sc.ext_x[o], sc.ext_y[o], sc.ext_z[o]);
    result.max_residual_mn = std::max(result.max_residual_mn, st.force.norm());
  }
  for (uint32_t v : sc.order) sc.layer_of[v] = -1;
  return result;
}

}  // namespace phaco::force_propagation
