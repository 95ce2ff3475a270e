#pragma once
// A drill's difficulty as eye parameters (issue 7 item 1; docs/drills.md). Seed 004 §1 names the
// anomalies that make a capsulorhexis hard — patient age, anterior bowing of the lens diaphragm, a
// shallow anterior chamber — and phaco-sculpting adds nucleus hardness. Each setting moves eye
// parameters within published ranges:
//
//   patient_age_years  capsule Young's modulus, linear between DESIGN.md §6's anchors, ≈ 6 MPa at
//                      10 years and 1.5 MPa at 80 (Krag, Olsen & Andreassen, IOVS 38:357, 1997:
//                      stiffness and strength of the anterior capsule fall with age), clamped to
//                      [1.5, 6] MPa; the ultimate stress scales with it, so the strain at which
//                      the capsule tears stays the eye file's (tear strength falls with age); so
//                      does the tearing energy (G_c = σ_u·δ_c, a cohesive zone of fixed critical
//                      opening δ_c), hence the tear resistance F_c = G_c·h/2 (systems/tear).
//   anterior_bowing_kpa a posterior (vitreous) pressure P pushing the lens diaphragm forward; the
//                      anterior capsule, a membrane of radius R = a²/c at the lens pole (a the
//                      equatorial radius, c the anterior half-thickness), carries Laplace's
//                      tension T = P·R/2, i.e. an extra in-plane strain T·(1 − ν)/(E·h) added to
//                      capsule_model.prestretch: the stretched membrane pulls the tear outward.
//   anterior_chamber_depth_mm  cornea.posterior_apex_z_mm = lens pole + depth (3.0 standard;
//                      < 2.5 shallow): less room between the endothelium and the capsule.
//   nucleus_hardness   lens_model.nucleus_hardness (0.5 standard; the tetrahedral sculpting scene
//                      removes less per stroke in a harder nucleus,
//                      procedures/scene/lens_sculpting).
//
// Reads and writes: eye parameters.
#include "engine/io/scenario.hpp"
#include "procedures/eye/eye_params.hpp"

namespace phaco::eye {

// Age → capsule Young's modulus, kPa (the linear model above).
double capsule_modulus_for_age_kpa(double age_years);

// Applies the present settings; absent ones leave the parameters alone.
void apply_difficulty(EyeParams& params, const DifficultySettings& settings);

}  // namespace phaco::eye
