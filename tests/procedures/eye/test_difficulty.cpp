// Difficulty settings as eye parameters (procedures/eye/difficulty.hpp, docs/drills.md): each
// setting moves exactly its parameters, by the model's formula, and nothing else.
#include <gtest/gtest.h>

#include "procedures/eye/difficulty.hpp"
#include "systems/tear/tear.hpp"

namespace phaco::eye {
namespace {

// Keys that differ between two parameter sets.
std::vector<std::string> changed(const EyeParams& a, const EyeParams& b) {
  std::vector<std::string> out;
  for (const auto& [key, value] : a.values)
    if (b.values.at(key) != value) out.push_back(key);
  return out;
}

TEST(Difficulty, AgeMovesTheCapsuleModulusBetweenThePublishedAnchors) {
  EXPECT_DOUBLE_EQ(capsule_modulus_for_age_kpa(10), 6000);  // children, DESIGN.md §6
  EXPECT_DOUBLE_EQ(capsule_modulus_for_age_kpa(80), 1500);  // elderly
  EXPECT_DOUBLE_EQ(capsule_modulus_for_age_kpa(45), 3750);  // linear between them
  EXPECT_DOUBLE_EQ(capsule_modulus_for_age_kpa(2), 6000) << "clamped";
  EXPECT_DOUBLE_EQ(capsule_modulus_for_age_kpa(99), 1500) << "clamped";
  // Monotone: older is never stiffer.
  for (double age = 1; age < 100; age += 1)
    EXPECT_LE(capsule_modulus_for_age_kpa(age + 1), capsule_modulus_for_age_kpa(age));
}

TEST(Difficulty, AgeScalesTheTearStrengthWithTheModulus) {
  const EyeParams standard = default_eye_params();
  EyeParams p = standard;
  DifficultySettings s;
  s.patient_age_years = 25;
  apply_difficulty(p, s);
  const double e = capsule_modulus_for_age_kpa(25);
  EXPECT_DOUBLE_EQ(p.get("capsule.youngs_modulus_kpa"), e);
  const double ratio = e / standard.get("capsule.youngs_modulus_kpa");
  EXPECT_NEAR(p.get("capsule.ultimate_stress_kpa"),
              standard.get("capsule.ultimate_stress_kpa") * ratio, 1e-9);
  // The strain at which the capsule tears is the eye file's.
  EXPECT_NEAR(
      p.get("capsule.ultimate_stress_kpa") / p.get("capsule.youngs_modulus_kpa"),
      standard.get("capsule.ultimate_stress_kpa") / standard.get("capsule.youngs_modulus_kpa"),
      1e-12);
  EXPECT_NEAR(p.get("capsule.tear_energy_j_m2"), standard.get("capsule.tear_energy_j_m2") * ratio,
              1e-9);
  EXPECT_EQ(changed(standard, p),
            (std::vector<std::string>{"capsule.tear_energy_j_m2", "capsule.ultimate_stress_kpa",
                                      "capsule.youngs_modulus_kpa"}));
}

// The tear resistance F_c = G_c·h/2 (systems/tear) follows the age through G_c: a child's stiffer
// capsule resists the tear more than the standard eye's, an 88-year-old's less.
TEST(Difficulty, AYoungerStifferCapsuleHasAHigherTearResistance) {
  const EyeParams standard = default_eye_params();
  auto resistance = [&](double age) {
    EyeParams p = standard;
    DifficultySettings s;
    s.patient_age_years = age;
    apply_difficulty(p, s);
    return tear::tear_resistance_mn(p.get("capsule.tear_energy_j_m2"),
                                    p.get("capsule.thickness_mm"));
  };
  const double standard_fc = tear::tear_resistance_mn(standard.get("capsule.tear_energy_j_m2"),
                                                      standard.get("capsule.thickness_mm"));
  EXPECT_NEAR(standard_fc, 0.5 * 1500 * 0.013, 1e-9) << "the eye file's G_c = 1500 J/m², h = 13 um";
  EXPECT_GT(resistance(10), resistance(25));
  EXPECT_GT(resistance(25), standard_fc);
  EXPECT_LT(resistance(88), standard_fc);
  // In proportion to the modulus.
  EXPECT_NEAR(resistance(10) / resistance(80),
              capsule_modulus_for_age_kpa(10) / capsule_modulus_for_age_kpa(80), 1e-9);
}

TEST(Difficulty, BowingAddsLaplaceStrainToThePrestretch) {
  const EyeParams standard = default_eye_params();
  EyeParams p = standard;
  DifficultySettings s;
  s.anterior_bowing_kpa = 0.4;
  apply_difficulty(p, s);
  // By hand for the standard eye: R = a²/c = 4.7²/1.8 = 12.272 mm; T = P·R/2 = 2.4544 mN/mm
  // (1 kPa = 1 mN/mm²); E·h = 2000 · 0.013 = 26 mN/mm; strain = T·(1 − 0.47)/26 = 0.050033.
  const double r = 4.7 * 4.7 / 1.8, t = 0.4 * r / 2.0, strain = t * (1 - 0.47) / 26.0;
  EXPECT_NEAR(strain, 0.050033, 1e-6);
  EXPECT_NEAR(p.get("capsule_model.prestretch"), standard.get("capsule_model.prestretch") + strain,
              1e-12);
  EXPECT_EQ(changed(standard, p), std::vector<std::string>{"capsule_model.prestretch"});
  // A stiffer (younger) capsule stretches less under the same pressure.
  EyeParams young = standard;
  s.patient_age_years = 10;
  apply_difficulty(young, s);
  EXPECT_NEAR(young.get("capsule_model.prestretch") - standard.get("capsule_model.prestretch"),
              strain * 2000.0 / 6000.0, 1e-12);
}

TEST(Difficulty, ChamberDepthAndHardness) {
  const EyeParams standard = default_eye_params();
  EyeParams p = standard;
  DifficultySettings s;
  s.anterior_chamber_depth_mm = 3.0;  // the standard eye's own depth: nothing moves
  apply_difficulty(p, s);
  EXPECT_TRUE(changed(standard, p).empty());
  s.anterior_chamber_depth_mm = 2.2;
  s.nucleus_hardness = 0.9;
  apply_difficulty(p, s);
  EXPECT_DOUBLE_EQ(p.get("cornea.posterior_apex_z_mm"), 1.8 + 2.2);
  EXPECT_DOUBLE_EQ(p.get("lens_model.nucleus_hardness"), 0.9);
  EXPECT_EQ(changed(standard, p), (std::vector<std::string>{"cornea.posterior_apex_z_mm",
                                                            "lens_model.nucleus_hardness"}));
  EyeParams untouched = standard;
  apply_difficulty(untouched, DifficultySettings{});
  EXPECT_TRUE(changed(standard, untouched).empty()) << "no settings, no change";
}

}  // namespace
}  // namespace phaco::eye
