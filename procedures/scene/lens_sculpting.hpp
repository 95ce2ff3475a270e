#pragma once
// Phaco-sculpting the tetrahedral lens in the running scene (issue 5; seed 000 §5.3–5.4).
//
// The lens keeps its rest shape in its own frame; the nucleus turns about the optical axis, so the
// scene's lens particles are the rest vertices rotated by the nucleus angle. Each frame, for the
// phaco probe:
//   - ultrasound on (pedal 3, seed 000: the tip's bounding sphere models the power): the tip, taken
//     into the lens frame, sculpts — systems/sculpt removes the tets it sweeps (broadphase on the
//     first contact, then a walk over face neighbours from the last removals) and keeps the surface
//     list; the nucleus's moment of inertia loses m·r² per removed tet;
//   - ultrasound off: the tip pushes the trench wall ahead of it round the optical axis, a
//     kinematic contact against the bag's friction and damping (systems/nucleus/rotation.hpp):
//     the wall cannot pass the tip, and the tip cannot throw the nucleus.
// Removed tets are kept with the stroke (a continuous period of ultrasound) that removed them, for
// the trench measures (procedures/lens/trench_measure).
//
// Methods (scenario `methods`): lens.broadphase octree | dbvt (default octree);
// lens.narrowphase centre | exact_gjk | exact_mpr (default centre, the seed's test).
// Parameters (eye file, lens_model.*): ultrasound_power (0..1], damping_torque_mn_mm (the bag's
// Coulomb friction), bag_damping_mn_mm_s (its viscous damping).
#include <cstdint>
#include <nlohmann/json.hpp>
#include <optional>
#include <vector>

#include "components/tet_topology.hpp"
#include "engine/schedule/system.hpp"
#include "procedures/lens/trench_measure.hpp"
#include "systems/nucleus/rotation.hpp"
#include "systems/sculpt/sculpt.hpp"

namespace phaco {

struct Scene;

// The standard eye's nucleus hardness (data/eye/standard_eye.json lens_model.nucleus_hardness):
// the hardness at which the lens's and the haptic contacts' settings hold as given.
inline constexpr double kStandardHardness = 0.5;

struct LensSculpting {
  TetTopology topology;
  sculpt::SculptState sculpt;
  std::vector<Vec3> rest;  // lens vertices in the lens frame, mm
  nucleus::NucleusRotation rotation;
  nucleus::RotationSettings push;
  double ultrasound_power = 1.0;
  lens::NucleusShape nucleus;
  std::optional<Vec3> previous_tip;    // lens frame, last frame with ultrasound on
  std::optional<Vec3> previous_probe;  // world, last frame without ultrasound
  std::vector<Vec3> wall;              // scratch: alive tet centres in the tip's sphere
  bool ultrasound_was_on = false;
  uint32_t strokes = 0;
  std::vector<lens::RemovedElement> removed;  // rest centre, volume, stroke of every removed tet
  // Figures for the report.
  uint64_t sculpt_steps = 0, push_frames = 0;
  double ultrasound_time_s = 0, volume_removed_mm3 = 0;
  double sculpt_ms_total = 0, sculpt_ms_max = 0;
  uint32_t max_removed_per_step = 0;
};

// Adds LensSculpting to the lens body; throws InputError for an unknown method choice.
void add_lens_sculpting(Scene& scene);

// Topology phase: reads tools.pose; writes lens.tets, lens.particles.
SystemDesc lens_sculpt_system(Scene& scene);

// The trenches so far (lens frame).
lens::TrenchReport lens_trenches(const Scene& scene);

// For the run report: removals, ultrasound time, nucleus rotation, trenches; null without a lens.
nlohmann::json lens_sculpting_summary(Scene& scene);

}  // namespace phaco
