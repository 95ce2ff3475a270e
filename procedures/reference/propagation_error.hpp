#pragma once
// Force propagation (systems/force_propagation, seed 000 §5.1) against the converged static
// equilibrium (static_solve), for a grasp: the centre vertex of a pre-stretched, rim-pinned flat
// disc and its spring neighbours are moved by grasp_move_mm and held; everything else finds its
// place. The disc is first relaxed in plane so both methods start from equilibrium.
//
// For every (max_layers, sweeps) pair the FPM result is compared with the equilibrium over all
// vertices: RMS and max of |x_fpm − x_eq|, also divided by |grasp_move|, and the work it did
// (nodes touched, node relaxations, wall time). max_layers = 0 is the baseline "only the grasped
// vertices moved".
#include <cstdint>
#include <vector>

#include "components/springs.hpp"
#include "procedures/reference/flat_disc.hpp"

namespace phaco::reference {

struct PropagationCase {
  int level = 3;
  DiscLayout layout = DiscLayout::Isotropic;
  StiffnessWeighting weighting = StiffnessWeighting::AreaWeighted;
  SpringLaw law = SpringLaw::Linear;
  double radius_mm = 4.5;
  double prestretch = 0.05;
  double sheet_modulus_mn_mm = 26.0;
  double grasp_move_mm[3] = {0.02, 0.0, 0.1};  // lift with a little pull
  std::vector<int> layers = {0, 1, 2, 4, 8, 16, 32};
  std::vector<int> sweeps = {1, 4, 16};
  double relaxation = 1.0;
  double tolerance_mm = 1e-7;
};

struct PropagationErrorRow {
  int level = 0;
  uint32_t vertices = 0;
  int max_layers = 0, sweeps = 0;
  double relaxation = 1.0;
  int layers_reached = 0;
  uint32_t nodes_touched = 0;
  uint64_t node_updates = 0;
  double seconds = 0.0;
  double rms_error_mm = 0.0, max_error_mm = 0.0;
  double rms_rel = 0.0, max_rel = 0.0;  // divided by |grasp_move|
  double max_residual_mn = 0.0;         // FPM's
};

struct PropagationStudy {
  std::vector<PropagationErrorRow> rows;  // layers × sweeps, in that order
  double reference_residual_mn = 0.0;     // of the static equilibrium
  uint32_t grasped = 0;                   // vertices held by the grasp
  double max_equilibrium_move_mm = 0.0;   // largest displacement in the equilibrium
};

PropagationStudy propagation_error_study(const PropagationCase& c);

}  // namespace phaco::reference
