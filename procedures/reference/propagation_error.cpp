#include "procedures/reference/propagation_error.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>

#include "procedures/reference/static_solve.hpp"
#include "systems/force_propagation/force_propagation.hpp"
#include "systems/springs/springs.hpp"

namespace phaco::reference {

PropagationStudy propagation_error_study(const PropagationCase& c) {
  PropagationStudy study;
  const FlatDisc disc = make_flat_disc(c.radius_mm, 1000u << c.level, c.layout);
  DiscBody body = make_disc_body(disc);
  Particles& p = body.particles;
  const Springs springs = springs::build_springs(
      p, body.triangles,
      springs::SpringMaterial{c.law, c.weighting, c.sheet_modulus_mn_mm, c.prestretch});
  const uint32_t n = p.slots.size();

  // Start from the in-plane equilibrium.
  StaticNetwork relaxed = network_from(p, springs, c.law);
  relaxed.planar = true;
  solve_static(relaxed, {1e-11, 60});
  for (uint32_t v = 0; v < n; ++v) {
    p.x[v] = static_cast<float>(relaxed.x[v].x());
    p.y[v] = static_cast<float>(relaxed.x[v].y());
    p.z[v] = static_cast<float>(relaxed.x[v].z());
  }

  // The grasp: centre vertex and its neighbours, scripted.
  const SpringGraph graph = springs::build_spring_graph(springs, n);
  std::vector<uint32_t> grasp = {0};
  for (uint32_t r = graph.begin(0); r < graph.end(0); ++r) grasp.push_back(graph.neighbour[r]);
  study.grasped = static_cast<uint32_t>(grasp.size());
  const Vec3 move(c.grasp_move_mm[0], c.grasp_move_mm[1], c.grasp_move_mm[2]);
  for (uint32_t v : grasp) {
    p.kind[v] = ParticleKind::Scripted;
    p.x[v] = static_cast<float>(p.x[v] + move.x());
    p.y[v] = static_cast<float>(p.y[v] + move.y());
    p.z[v] = static_cast<float>(p.z[v] + move.z());
  }

  // Reference: the equilibrium with the grasp held (positions as the FPM sees them).
  StaticNetwork eq = network_from(p, springs, c.law);
  const StaticResult ref = solve_static(eq, {1e-10, 60});
  study.reference_residual_mn = ref.residual_mn;
  for (uint32_t v = 0; v < n; ++v)
    study.max_equilibrium_move_mm =
        std::max(study.max_equilibrium_move_mm, (eq.x[v] - Vec3(p.x[v], p.y[v], p.z[v])).norm());

  const Particles start = p;
  force_propagation::PropagationScratch scratch;
  for (int layers : c.layers)
    for (int sweeps : c.sweeps) {
      Particles q = start;
      force_propagation::PropagationResult res;
      const auto t0 = std::chrono::steady_clock::now();
      if (layers > 0)
        res = force_propagation::propagate(q, springs, c.law, graph, grasp,
                                           {layers, sweeps, c.tolerance_mm, c.relaxation}, scratch);
      const double seconds =
          std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
      PropagationErrorRow row;
      row.level = c.level, row.vertices = n, row.max_layers = layers, row.sweeps = sweeps;
      row.relaxation = c.relaxation, row.layers_reached = res.layers_reached;
      row.nodes_touched = res.nodes_touched, row.node_updates = res.node_updates;
      row.seconds = seconds, row.max_residual_mn = res.max_residual_mn;
      double sum2 = 0.0;
      for (uint32_t v = 0; v < n; ++v) {
        const double e = (eq.x[v] - Vec3(q.x[v], q.y[v], q.z[v])).norm();
        sum2 += e * e;
        row.max_error_mm = std::max(row.max_error_mm, e);
      }
      row.rms_error_mm = std::sqrt(sum2 / n);
      row.rms_rel = row.rms_error_mm / move.norm();
      row.max_rel = row.max_error_mm / move.norm();
      study.rows.push_back(row);
    }
  return study;
}

}  // namespace phaco::reference
