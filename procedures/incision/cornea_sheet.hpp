#pragma once
// The cornea as the keratome cuts it (issue 4 item 2): the closed shell of procedures/eye
// (anterior cap, limbus rim band, posterior cap: one closed, outward-facing surface, every vertex
// on its analytic surface) as a cuttable membrane, its spheres for the blade geometry, and the
// membrane material taken from the eye file.
//
// Material: the shell's two caps stand for one stroma of thickness h (cornea.central_thickness_mm),
// so each cap carries half of it: sheet modulus E·h/2, areal density ρ·h/2
// (cornea.youngs_modulus_kpa, cornea.density_kg_m3). The pre-stretch is the capsule model's
// (capsule_model.prestretch, 3 %): the same order as the strain intra-ocular pressure puts in the
// cornea (15 mmHg = 2 kPa gives a membrane tension p·R/2 = 7.8 mN/mm, a strain of about
// (1 − ν)·7.8 / (E·h) ≈ 2 % at E = 400 kPa), so a cut gapes as seed 000 §5.2 says.
//
// Reads: eye parameters. Writes: a new MembraneSheet.
#include "procedures/eye/eye_params.hpp"
#include "systems/cut/membrane_sheet.hpp"
#include "systems/incision/keratome.hpp"
#include "systems/incision/wound.hpp"

namespace phaco::corneal_incision {

// The anterior and posterior corneal spheres and the limbus radius (eye::EyeGeometry).
incision::CorneaSpheres cornea_spheres(const eye::EyeParams& params);

// E·h/2 and ρ·h/2 per cap, the capsule model's pre-stretch (cotangent pre-tension, as the capsule).
cut::MembraneMaterial cornea_material(const eye::EyeParams& params);

// The keratome of the eye file (tools.keratome_width_mm; other sizes KeratomeShape's defaults).
incision::KeratomeShape eye_keratome(const eye::EyeParams& params);

// eye::make_cornea at the level's resolution as a membrane with cornea_material. Throws
// phaco::InputError for a level outside [kMinLevel, kMaxLevel].
cut::MembraneSheet make_cornea_sheet(const eye::EyeParams& params, int level);

}  // namespace phaco::corneal_incision
