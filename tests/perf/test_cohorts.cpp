// The cohort study's pieces (perf/cohorts, issue 20 item 4): members carry the tremor the spec
// asks for (RMS transverse and axial, 8–12 Hz), their tempo and offset, deterministically per
// seed; the ROC AUC and the contrasting-groups cut-off on known groups.
#include <gtest/gtest.h>

#include <cmath>

#include "perf/cohorts/cohort.hpp"

namespace phaco::perf {
namespace {

Scenario resting_tool(double duration_s) {
  Scenario s;
  s.dt_s = 1.0 / 120.0;
  s.duration_s = duration_s;
  HandTrack h;
  h.tool = ToolKind::PhacoProbe;
  TrackSample a;
  a.pos = Vec3(1, 2, 3);
  a.quat = Quat(Eigen::AngleAxisd(0.7, Vec3::UnitY()));
  h.track = {a};
  s.hands = {h};
  return s;
}

TEST(Cohorts, MembersShakeAtTheSpecsTremorAndVaryTheirTempo) {
  const Scenario base = resting_tool(4.0);
  for (const CohortSpec& spec : {expert_spec(), novice_spec()}) {
    const Scenario m = cohort_member(base, spec, 7);
    EXPECT_NEAR(m.duration_s, 4.0, 4.0 * spec.time_scale_spread + 1e-9);
    const Vec3 shaft = base.hands[0].track[0].quat * Vec3::UnitZ();
    // The tremor about the member's own (offset) mean position.
    Vec3 centre = Vec3::Zero();
    for (const auto& s : m.hands[0].track) centre += s.pos;
    centre /= double(m.hands[0].track.size());
    double axial = 0, transverse = 0;
    int crossings = 0;
    double last = 0;
    for (const auto& s : m.hands[0].track) {
      const Vec3 d = s.pos - centre;
      const double along = d.dot(shaft);
      axial += along * along, transverse += (d - along * shaft).squaredNorm();
      crossings += (along > 0) != (last > 0);
      last = along;
    }
    const double k = double(m.hands[0].track.size());
    EXPECT_NEAR(std::sqrt(transverse / k), spec.tremor_transverse_rms_mm,
                0.1 * spec.tremor_transverse_rms_mm);
    EXPECT_NEAR(std::sqrt(axial / k), spec.tremor_axial_rms_mm, 0.1 * spec.tremor_axial_rms_mm);
    // 8–12 Hz: 16–24 sign changes a second.
    const double hz = crossings / (2 * m.duration_s);
    EXPECT_GT(hz, 7.5);
    EXPECT_LT(hz, 12.5);
    EXPECT_EQ(cohort_member(base, spec, 7).hands[0].track.back().pos, m.hands[0].track.back().pos)
        << "deterministic in the seed";
    EXPECT_NE(cohort_member(base, spec, 8).hands[0].track.back().pos, m.hands[0].track.back().pos);
  }
}

TEST(Cohorts, AucAndContrastingGroupsCutOff) {
  EXPECT_DOUBLE_EQ(roc_auc({3, 4}, {1, 2}), 1.0);
  EXPECT_DOUBLE_EQ(roc_auc({1, 2}, {3, 4}), 0.0);
  EXPECT_DOUBLE_EQ(roc_auc({1, 3}, {2}), 0.5);
  EXPECT_DOUBLE_EQ(roc_auc({2, 2}, {2}), 0.5) << "ties count half";
  EXPECT_TRUE(std::isnan(roc_auc({}, {1})));
  // Equal spreads: the densities cross half-way.
  EXPECT_NEAR(contrasting_groups_cutoff({85, 90, 95}, {45, 50, 55}), 70.0, 1e-9);
  // A tight expert group: the crossing moves toward it, still between the means.
  const double c = contrasting_groups_cutoff({99, 100, 101}, {40, 60, 80});
  EXPECT_GT(c, 80.0);
  EXPECT_LT(c, 100.0);
  EXPECT_TRUE(std::isnan(contrasting_groups_cutoff({}, {1})));
}

}  // namespace
}  // namespace phaco::perf
