#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <fstream>
#include <functional>
#include <limits>
#include <numbers>
#include <stdexcept>
#include <string>

#include "engine/core/error.hpp"
#include "eye_test_util.hpp"
#include "procedures/eye/eye_geometry.hpp"
#include "procedures/eye/eye_param_ranges.hpp"
#include "procedures/eye/eye_params.hpp"
#include "procedures/eye/resolution.hpp"
#include "tests/support/expect_invalid.hpp"

namespace phaco::eye {
namespace {

using phaco::test::input_error_of;

TEST(EyeParams, StandardEyeHasDesignValues) {
  const EyeParams p = default_eye_params();
  EXPECT_DOUBLE_EQ(p.get("lens.equatorial_diameter_mm"), 9.4);
  EXPECT_DOUBLE_EQ(p.get("lens.anterior_half_thickness_mm"), 1.8);
  EXPECT_DOUBLE_EQ(p.get("lens.posterior_half_thickness_mm"), 2.7);
  EXPECT_DOUBLE_EQ(p.get("capsule.youngs_modulus_kpa"), 2000);
  EXPECT_DOUBLE_EQ(p.get("capsule.radius_mm"), 4.5);
  EXPECT_DOUBLE_EQ(p.get("cornea.posterior_apex_z_mm"), 4.8);
  EXPECT_DOUBLE_EQ(p.get("globe.axial_length_mm"), 23.5);
  EXPECT_DOUBLE_EQ(p.get("tools.keratome_width_mm"), 2.4);
  // Targets are the drills' (data/drills), not the eye's.
  EXPECT_EQ(p.values.count("targets.trench_crossing_angle_deg"), 0u);
  EXPECT_EQ(p.values.size(), required_eye_keys().size());
}

TEST(EyeParams, GetNamesMissingKey) {
  const EyeParams p = default_eye_params();
  try {
    p.get("lens.no_such_key");
    FAIL() << "expected std::out_of_range";
  } catch (const std::out_of_range& e) {
    EXPECT_NE(std::string(e.what()).find("lens.no_such_key"), std::string::npos);
  }
}

TEST(EyeParams, DataDirFollowsEnvironment) {
  const char* old = std::getenv("PHACO_DATA_DIR");
  const std::string saved = old ? old : "";
  ::setenv("PHACO_DATA_DIR", "/nonexistent/phaco-data", 1);
  EXPECT_EQ(data_dir(), std::filesystem::path("/nonexistent/phaco-data"));
  EXPECT_THROW(default_eye_params(), InputError);
  if (old) {
    ::setenv("PHACO_DATA_DIR", saved.c_str(), 1);
  } else {
    ::unsetenv("PHACO_DATA_DIR");
  }
  EXPECT_TRUE(std::filesystem::exists(data_dir() / "eye" / "standard_eye.json"));
}

// Issue 23: without PHACO_DATA_DIR, a test (an executable inside the build tree, with no
// ../share/openphaco beside it) reads the source tree's data/; tests/apps/test_install.cpp checks
// a copy outside the build tree does not.
TEST(EyeParams, AnExecutableInTheBuildTreeReadsTheSourceData) {
  const char* old = std::getenv("PHACO_DATA_DIR");
  const std::string saved = old ? old : "";
  ::unsetenv("PHACO_DATA_DIR");
  const phaco::eye::DataDir d = phaco::eye::locate_data_dir();
  if (old) ::setenv("PHACO_DATA_DIR", saved.c_str(), 1);
  EXPECT_EQ(d.origin, "build tree");
  EXPECT_EQ(std::filesystem::weakly_canonical(d.dir),
            std::filesystem::weakly_canonical(std::filesystem::path(PHACO_SOURCE_DIR) / "data"));
}

// A copy of the standard file with one line edited, and the text the error must contain.
struct BadFile {
  const char* name;
  const char* from;  // substring of the standard file to replace
  const char* to;
  const char* expect;
};

TEST(EyeParams, LoadRejectsBadFilesNamingFileAndPath) {
  const auto standard = data_dir() / "eye" / "standard_eye.json";
  std::ifstream in(standard);
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const BadFile cases[] = {
      {"negative", "\"thickness_mm\": 0.013", "\"thickness_mm\": -0.013", "/capsule/thickness_mm"},
      {"zero", "\"z_mm\": 1.8", "\"z_mm\": 0", "/iris/z_mm"},
      {"out of range", "\"youngs_modulus_kpa\": 2000", "\"youngs_modulus_kpa\": 1e300",
       "/capsule/youngs_modulus_kpa: expected a number in 100..20000"},
      {"string", "\"radius_mm\": 12.0", "\"radius_mm\": \"twelve\"", "/globe/radius_mm"},
      {"missing", "\"nucleus_fraction\": 0.7,", "", "/lens/nucleus_fraction"},
      {"syntax", "\"lens\": {", "\"lens\": {{", "invalid JSON"},
      {"section",
       "\"tools\": {\n    \"phaco_tip_diameter_mm\": 0.9,\n    \"keratome_width_mm\": 2.4,\n    "
       "\"cystotome_tip_mm\": 0.3\n  }",
       "\"tools\": 3", "/tools"},
  };
  test::ScratchDir dir("eye_params");
  for (const auto& c : cases) {
    std::string edited = text;
    const auto at = edited.find(c.from);
    ASSERT_NE(at, std::string::npos) << c.name;
    edited.replace(at, std::string(c.from).size(), c.to);
    const auto file = dir.path() / (std::string(c.name) + ".json");
    std::ofstream(file) << edited;
    const std::string msg = input_error_of([&] { load_eye_params(file); });
    EXPECT_NE(msg.find(file.string()), std::string::npos) << c.name << ": " << msg;
    EXPECT_NE(msg.find(c.expect), std::string::npos) << c.name << ": " << msg;
  }
  const std::string missing = input_error_of([&] { load_eye_params(dir.path() / "absent.json"); });
  EXPECT_NE(missing.find("absent.json"), std::string::npos) << missing;
}

TEST(EyeParams, OverrideAcceptsKnownPositiveFiniteValues) {
  EyeParams p = default_eye_params();
  apply_override(p, "capsule.youngs_modulus_kpa", 3000);
  EXPECT_DOUBLE_EQ(p.get("capsule.youngs_modulus_kpa"), 3000);

  const std::string unknown = input_error_of([&] { apply_override(p, "capsule.stiffness", 1.0); });
  EXPECT_NE(unknown.find("unknown eye parameter 'capsule.stiffness'"), std::string::npos)
      << unknown;
  EXPECT_NE(unknown.find("capsule.youngs_modulus_kpa"), std::string::npos) << "lists known keys";

  EXPECT_THROW(apply_override(p, "lens.nucleus_fraction", std::nan("")), InputError);
  EXPECT_THROW(apply_override(p, "lens.nucleus_fraction", std::numeric_limits<double>::infinity()),
               InputError);
  EXPECT_THROW(apply_override(p, "lens.nucleus_fraction", -0.5), InputError);
  EXPECT_THROW(apply_override(p, "lens.nucleus_fraction", 0.0), InputError);
  EXPECT_DOUBLE_EQ(p.get("lens.nucleus_fraction"), 0.7) << "a rejected override changes nothing";
}

TEST(EyeParams, GeometryRejectsInconsistentEyes) {
  EyeParams p = default_eye_params();
  EXPECT_NO_THROW(eye_geometry(p));
  apply_override(p, "capsule.radius_mm", 5.0);  // wider than the lens (a = 4.7)
  const std::string msg = input_error_of([&] { eye_geometry(p); });
  EXPECT_NE(msg.find("capsule.radius_mm"), std::string::npos) << msg;

  EyeParams q = default_eye_params();
  apply_override(q, "iris.pupil_diameter_mm", 12.0);  // pupil wider than the iris
  EXPECT_THROW(eye_geometry(q), InputError);
  EyeParams r = default_eye_params();
  apply_override(r, "cornea.posterior_apex_z_mm", 3.0);       // each in range; the cornea
  apply_override(r, "lens.anterior_half_thickness_mm", 3.5);  // behind the lens's front
  EXPECT_THROW(eye_geometry(r), InputError);
}

// Issue 18 item 1: every eye parameter has a physical range; its edges are accepted, and a value
// just past either edge is refused with the key and the range, leaving the value unchanged.
TEST(EyeParams, EveryParameterHasARangeWithItsEdgesAcceptedAndJustPastRefused) {
  const EyeParams standard = default_eye_params();
  ASSERT_EQ(eye_param_ranges().size(), required_eye_keys().size());
  for (const EyeParamRange& r : eye_param_ranges()) {
    const std::string key(r.key);
    ASSERT_LT(r.lo, r.hi) << key;
    ASSERT_GT(r.lo, 0.0) << key << ": every eye quantity is positive";
    const double v = standard.get(key);
    EXPECT_TRUE(v >= r.lo && v <= r.hi) << key << " = " << v << ": the standard eye is in range";
    for (const double edge : {r.lo, r.hi}) {
      EyeParams p = standard;
      EXPECT_NO_THROW(apply_override(p, key, edge)) << key << " = " << edge;
      EXPECT_EQ(p.get(key), edge) << key;
    }
    for (const double past : {r.lo * (1 - 1e-9), r.hi * (1 + 1e-9), 1e300}) {
      EyeParams p = standard;
      const std::string msg = input_error_of([&] { apply_override(p, key, past); });
      EXPECT_NE(msg.find("expected a number in "), std::string::npos) << key << ": " << msg;
      EXPECT_NE(msg.find("(the physical range of " + key + ")"), std::string::npos) << msg;
      EXPECT_EQ(p.get(key), v) << key << ": a refused override changes nothing";
    }
  }
  EyeParams p = standard;
  EXPECT_EQ(input_error_of([&] { apply_override(p, "capsule.youngs_modulus_kpa", 1e6); }),
            "expected a number in 100..20000 (the physical range of capsule.youngs_modulus_kpa), "
            "got 1e+06");
}

TEST(EyeGeometry, DerivedLengthsMatchDesign) {
  const EyeGeometry g = eye_geometry(default_eye_params());
  EXPECT_NEAR(g.cornea_anterior_apex_z, 5.33, 1e-12);
  EXPECT_NEAR(g.iris_outer_radius, std::sqrt(30.0), 1e-12);  // 6.5² - (1.8 + 1.7)²
  EXPECT_NEAR(g.globe_centre_z, 5.33 - 23.5 + 12.0, 1e-12);
  EXPECT_NEAR(g.lens_volume(), 2.0 / 3.0 * std::numbers::pi * 4.7 * 4.7 * 4.5, 1e-9);
}

TEST(Resolution, LevelsDoubleAndBoundsAreChecked) {
  EXPECT_EQ(resolution_for_level(3).capsule_vertices, 8000u);
  EXPECT_EQ(resolution_for_level(3).lens_tets, 50000u);
  EXPECT_EQ(resolution_for_level(7).capsule_vertices, 128000u);
  EXPECT_EQ(resolution_for_level(0).lens_tets, 6250u);
  for (int l = kMinLevel + 1; l <= kMaxLevel; ++l) {
    EXPECT_EQ(resolution_for_level(l).capsule_vertices,
              2 * resolution_for_level(l - 1).capsule_vertices);
  }
  EXPECT_THROW(resolution_for_level(-1), InputError);
  EXPECT_THROW(resolution_for_level(kMaxLevel + 1), InputError);
  EXPECT_EQ(kMaxLevel, 8);  // level 8: 256k capsule vertices, 1.6M lens tets (issue 9)
}

}  // namespace
}  // namespace phaco::eye
