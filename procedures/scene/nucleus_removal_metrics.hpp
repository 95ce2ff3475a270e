#pragma once
// The nucleus_removal drill's measures (issue 19 item 3; docs/metrics.md): sampled every frame by
// drill_metrics for the probe and the chopper, and its metrics at the end of the run.
//
// Per frame:
//   posterior capsule  the tip's distance inside the posterior capsule: below the bag's rim (where
//                      its anterior and posterior spheres meet, lens_tools::EyeBounds, what the
//                      fragments are held by) R − |p − c| for the posterior sphere, above it the
//                      distance to the rim circle. Below 0 the tip is through the capsule: a
//                      rupture (event posterior_capsule_rupture, once per tip), which fails the
//                      drill;
//   endothelium        the tip's distance inside the cornea's posterior sphere, counted only over
//                      the pupil (a tip at the limbus is in its port, where it touches the cornea
//                      on purpose): its minimum and the time closer than 1 mm;
//   anterior chamber   pieces of nucleus (kPieceMassFraction of the lens) not held at the tip whose
//                      centre of mass is out of the bag through the rhexis (above the anterior
//                      capsule's sphere): the most at once.
// At the end: time, fragments removed, volume removed (and its fraction of the grooved lens), CDE,
// aspiration time, the chopper's force (max, mean over the frames it pushed) and the above
// (posterior_capsule.rupture is the drill file's complication: drill_failed). Reads the lens's
// LensFragments and the tools' poses.
#include <cstdint>
#include <limits>
#include <nlohmann/json.hpp>
#include <span>
#include <vector>

#include "engine/ecs/world.hpp"
#include "systems/lens_tools/constraints.hpp"

namespace phaco {

struct Scene;

struct NucleusRemovalRecord {
  lens_tools::EyeBounds bounds;
  double pupil_radius_mm = 0;
  double rim_z_mm = 0, rim_radius_mm = 0;  // the bag's rim circle
  double posterior_min_distance_mm = std::numeric_limits<double>::infinity();
  double endothelium_min_distance_mm = std::numeric_limits<double>::infinity();
  double endothelium_near_s = 0;  // time with a tip closer than kEndotheliumNearMm
  uint32_t anterior_chamber_max = 0;
  bool ruptured = false;
  std::vector<uint8_t> through;  // per tool: its tip is through the posterior capsule
  // Per tool: where its tip first came behind the cornea's posterior surface (the wound's inner
  // opening, drill_events' rule); within wound_radius_mm of it the tip is in the incision, not at
  // the endothelium. A carried main port may open over the pupil.
  std::vector<Vec3> entry;
  std::vector<uint8_t> entered;
  double wound_radius_mm = 0;
  std::vector<double> fx, fy, fz;  // per fragment: mass-weighted centre (scratch)
};

inline constexpr double kEndotheliumNearMm = 1.0;

// Signed distance of a tip inside the posterior capsule (above).
double posterior_capsule_distance_mm(const NucleusRemovalRecord& r, const Vec3& tip);

NucleusRemovalRecord make_nucleus_removal_record(const Scene& scene);

// One frame; returns a bit per scene tool whose tip went through the posterior capsule this frame.
uint32_t sample_nucleus_removal(Scene& scene, NucleusRemovalRecord& r, double dt_s);

void nucleus_removal_metrics(Scene& scene, const NucleusRemovalRecord& r, nlohmann::json& metrics);

}  // namespace phaco
