// Tool–eye interaction (systems/tool_eye, seed 001 §3.2): a tool on the tunnel axis loads nothing;
// a lateral push through the slit reaches the closed-form linear equilibrium of the tunnel, hand
// and muscle springs, and the globe turns by exactly its torque over k_g; the linear CG agrees with
// a dense solve of the same quadratic; the lens and inner-cornea springs are one-sided and hold the
// tip where they should; degenerate inputs stay finite; a warm start is already converged.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <limits>
#include <vector>

#include "systems/tool_eye/tool_eye.hpp"

namespace phaco::tool_eye {
namespace {

// Converged to the fixed point (the scene's default stops at 1e-3 mN for its frame budget).
const SolverOptions kTight{.max_steps = 60, .max_cg = 4 * kUnknowns, .gradient_tol = 1e-10};

// A horizontal temporal port at 3 o'clock in the standard eye (DESIGN.md §6).
EyePort test_port() {
  EyePort p;
  p.name = "main";
  p.centre_mm = Vec3(5.5, 0.0, 2.4);
  p.axis = Vec3(-1.0, 0.0, 0.0);
  p.width_dir = Vec3(0.0, 1.0, 0.0);
  p.width_mm = 2.4;
  p.tunnel_length_mm = 1.75;
  return p;
}

EyePort side_port() {
  EyePort p = test_port();
  p.name = "side";
  p.centre_mm = Vec3(-2.75, 4.76, 2.4);
  p.axis = Vec3(0.5, -0.866, 0.0).normalized();
  p.width_dir = Vec3(0.866, 0.5, 0.0).normalized();
  p.width_mm = 1.2;
  return p;
}

EyeShape test_eye() {
  EyeShape e;
  e.globe_centre_mm = Vec3(0.0, 0.0, -6.17);
  e.cornea_centre_mm = Vec3(0.0, 0.0, -1.7);
  e.cornea_posterior_radius_mm = 6.5;
  e.lens_equator_radius_mm = 4.7;
  e.lens_anterior_mm = 1.8;
  e.lens_posterior_mm = 2.7;
  return e;
}

Stiffness standard() {
  Stiffness k;
  k.hand_mn_mm = 1000;
  k.hand_rot_mn_mm_rad = 1e5;
  k.tunnel_mn_mm = 200;
  k.tunnel_rot_mn_mm_rad = 50;
  k.tunnel_free_angle_rad = 10.0 * M_PI / 180.0;
  k.cornea_mn_mm = 200;
  k.lens_mn_mm = 100;
  k.globe_rot_mn_mm_rad = 6000;
  return k;
}

bool finite_state(const GlobeState& s) {
  if (!s.rotation.coeffs().allFinite() || !std::isfinite(s.energy_mn_mm)) return false;
  for (const auto& t : s.tools) {
    if (!t.tip_mm.allFinite() || !t.shaft.allFinite() || !t.port_force_mn.allFinite() ||
        !t.tip_offset_mm.allFinite() || !t.shaft_turn.coeffs().allFinite())
      return false;
  }
  return true;
}

TEST(ToolEye, ToolOnTheTunnelAxisLoadsNothing) {
  const std::vector<EyePort> ports = {test_port()};
  const EyePort& p = ports[0];
  HandPose hand{p.centre_mm + 1.5 * p.axis, -p.axis, -1};
  hand.port = engaged_port(ports, Quat::Identity(), test_eye().globe_centre_mm, hand.tip_mm,
                           hand.shaft, -1);
  ASSERT_EQ(hand.port, 0);
  GlobeState s;
  solve(ports, test_eye(), standard(), std::span<const HandPose>(&hand, 1), s, kTight);
  EXPECT_LT(rotation_vector(s.rotation).norm(), 1e-12);
  EXPECT_LT(s.tools[0].port_force_mn.norm(), 1e-9);
  EXPECT_LT((s.tools[0].tip_mm - hand.tip_mm).norm(), 1e-12);
  EXPECT_NEAR(s.energy_mn_mm, 0.0, 1e-12);
}

TEST(ToolEye, LateralPushMatchesTheLinearEquilibrium) {
  // Only the tunnel's translational spring and the muscles (and the hand holding the tool): the
  // shaft parallel to the axis, pushed δ0 through the slit (no free play that way).
  Stiffness k = standard();
  k.tunnel_rot_mn_mm_rad = 0, k.cornea_mn_mm = 0, k.lens_mn_mm = 0;
  const std::vector<EyePort> ports = {test_port()};
  const EyePort& p = ports[0];
  const EyeShape eye = test_eye();
  const Vec3 eh = p.axis.cross(p.width_dir);
  const double delta0 = 0.01, s = 1.5;  // a 10 µm push: θ ≈ 0.05°, linear to O(θ²)
  const HandPose hand{p.centre_mm + s * p.axis + delta0 * eh, -p.axis, 0};
  GlobeState st;
  solve(ports, eye, k, std::span<const HandPose>(&hand, 1), st, kTight);

  // Closed form: δ_h = −δ0 / (1 + k_t·C), C the hand's, the tool's turn about its tip and the
  // globe's compliances seen at the port; the globe turns by the port force's torque over k_g.
  const Vec3 rc = p.centre_mm - eye.globe_centre_mm, d = -p.axis;
  const double c = 1.0 / k.hand_mn_mm + (s * d).cross(eh).squaredNorm() / k.hand_rot_mn_mm_rad +
                   rc.cross(eh).squaredNorm() / k.globe_rot_mn_mm_rad;
  const double dh = -delta0 / (1.0 + k.tunnel_mn_mm * c);
  const Vec3 force = -k.tunnel_mn_mm * dh * eh;
  const Vec3 theta_linear = rc.cross(force) / k.globe_rot_mn_mm_rad;
  const Vec3 theta = rotation_vector(st.rotation);
  ASSERT_GT(theta.norm(), 1e-7);
  EXPECT_LT((theta - theta_linear).norm(), 1e-6)
      << theta.transpose() << " vs " << theta_linear.transpose();
  EXPECT_LT((st.tools[0].port_force_mn - force).norm(), 1e-3 * force.norm());
  // Equilibrium of the globe with the solver's own port force: θ = torque / k_g.
  // The force acts where the shaft passes the port (its closest point to the centre).
  const Vec3 c_now = eye.globe_centre_mm + st.rotation * rc;
  const Vec3 w = c_now - st.tools[0].tip_mm, dn = st.tools[0].shaft;
  const Vec3 at = st.tools[0].tip_mm + w.dot(dn) * dn;
  const Vec3 torque = (at - eye.globe_centre_mm).cross(st.tools[0].port_force_mn);
  EXPECT_LT((theta - torque / k.globe_rot_mn_mm_rad).norm(), 1e-6 * theta.norm());
}

TEST(ToolEye, ConjugateGradientEqualsADenseSolve) {
  // Several springs at once: the main tool tilted and off-centre with its tip in the lens, the
  // other in the side port pushed across the slit's width.
  const std::vector<EyePort> ports = {test_port(), side_port()};
  const EyePort& m = ports[0];
  const EyePort& sp = ports[1];
  const Vec3 tip0(1.0, 0.3, 1.2);  // inside the lens (anterior half)
  const Vec3 through = m.centre_mm + Vec3(0.0, 1.6, 0.2);
  const Vec3 tip1 = sp.centre_mm + 2.0 * sp.axis + Vec3(0.0, 0.0, 0.1);
  const std::array<HandPose, 2> hands = {
      HandPose{tip0, (through - tip0).normalized(), 0},
      HandPose{tip1, (sp.centre_mm + 1.0 * sp.width_dir - tip1).normalized(), 1}};
  GlobeState st;
  st.rotation = Quat(Eigen::AngleAxisd(0.01, Vec3(0.3, 1.0, 0.2).normalized()));
  st.tools[0].tip_offset_mm = Vec3(0.01, -0.02, 0.0);
  const Quadratic q = linearise(ports, test_eye(), standard(), hands, st);
  ASSERT_GT(q.gradient.norm(), 1e-3);
  const Vector dense = q.hessian.ldlt().solve(-q.gradient);
  Vector x = Vector::Zero();
  const int it = conjugate_gradient(q.hessian, -q.gradient, x, 4 * kUnknowns, 1e-15);
  EXPECT_LE(it, 4 * kUnknowns);
  EXPECT_LT((x - dense).norm(), 1e-9 * dense.norm()) << "CG iterations " << it;
  // The Hessian is symmetric positive definite.
  EXPECT_LT((q.hessian - q.hessian.transpose()).norm(), 1e-9 * q.hessian.norm());
  EXPECT_GT(q.hessian.ldlt().vectorD().minCoeff(), 0.0);
}

// A bent point (the chopper's 1 mm, engine/io/tool_shape): the tunnel holds the shaft's axis,
// beside the tip, not the line through the tip. With the axis on the tunnel's axis nothing is
// loaded although the tip's line runs 1 mm through the slit; the same pose read as the line
// through the tip, or the tip's line on the tunnel's axis with the shaft 1 mm through the slit,
// press the tunnel; and the gradient of E, with the axis point turning about the tip, is the
// energy's own (central differences).
TEST(ToolEye, ABentPointsShaftAxisIsWhatTheTunnelHolds) {
  const std::vector<EyePort> ports = {test_port()};
  const EyePort& p = ports[0];
  const EyeShape eye = test_eye();
  const Vec3 eh = p.axis.cross(p.width_dir);
  const Vec3 tip = p.centre_mm + 1.5 * p.axis + 1.0 * eh;  // 1 mm below the tunnel's axis
  HandPose bent{tip, -p.axis, -1, false, -1.0 * eh};
  bent.port = engaged_port(ports, Quat::Identity(), eye.globe_centre_mm, bent.tip_mm, bent.shaft,
                           -1, bent.axis_offset_mm);
  ASSERT_EQ(bent.port, 0);
  GlobeState st;
  solve(ports, eye, standard(), std::span<const HandPose>(&bent, 1), st, kTight);
  EXPECT_LT(st.tools[0].port_force_mn.norm(), 1e-9);
  EXPECT_LT(rotation_vector(st.rotation).norm(), 1e-12);

  HandPose tip_line = bent;
  tip_line.axis_offset_mm = Vec3::Zero();
  GlobeState st_line;
  solve(ports, eye, standard(), std::span<const HandPose>(&tip_line, 1), st_line, kTight);
  EXPECT_GT(st_line.tools[0].port_force_mn.norm(), 50.0);

  const HandPose off{p.centre_mm + 1.5 * p.axis, -p.axis, 0, false, 1.0 * eh};
  GlobeState st_off;
  solve(ports, eye, standard(), std::span<const HandPose>(&off, 1), st_off, kTight);
  EXPECT_GT(st_off.tools[0].port_force_mn.norm(), 50.0);

  // The gradient away from the equilibrium: tool and globe turned, the tip moved.
  GlobeState x;
  x.rotation = Quat(Eigen::AngleAxisd(0.02, Vec3(0.3, 1.0, 0.2).normalized()));
  x.tools[0].tip_offset_mm = Vec3(0.05, -0.1, 0.03);
  x.tools[0].shaft_turn = Quat(Eigen::AngleAxisd(0.1, Vec3(0.2, -0.5, 1.0).normalized()));
  const Quadratic q = linearise(ports, eye, standard(), std::span<const HandPose>(&off, 1), x);
  ASSERT_GT(q.gradient.norm(), 1.0);
  const double h = 1e-6;
  for (int i = 0; i < kUnknowns; ++i) {
    if (i >= 6 && i < 12) continue;  // the second tool's slot: no hand
    double e[2];
    for (int side = 0; side < 2; ++side) {
      GlobeState y = x;
      const double step = side == 0 ? h : -h;
      const Vec3 v = step * Vec3::Unit(i % 3);
      const Quat turn(Eigen::AngleAxisd(std::abs(step), v.normalized()));
      if (i < 3) y.tools[0].tip_offset_mm += v;
      if (i >= 3 && i < 6) y.tools[0].shaft_turn = turn * x.tools[0].shaft_turn;
      if (i >= 12) y.rotation = turn * x.rotation;
      e[side] = linearise(ports, eye, standard(), std::span<const HandPose>(&off, 1), y).energy;
    }
    EXPECT_NEAR((e[0] - e[1]) / (2 * h), q.gradient[i], 1e-4 * q.gradient.norm()) << i;
  }
}

TEST(ToolEye, TipPushedIntoTheLensEndsOutsideIt) {
  // The lens much stiffer than the hand, so the equilibrium is the constraint's.
  Stiffness k = standard();
  k.lens_mn_mm = 1e7;
  const std::vector<EyePort> ports = {test_port()};
  const EyeShape eye = test_eye();
  const Vec3 tip(2.0, 0.0, 0.8);  // 1.8·√(1 − (2/4.7)²) = 1.63 is the surface: 0.8 mm deep
  const HandPose hand{tip, (ports[0].centre_mm - tip).normalized(), 0};
  GlobeState st;
  solve(ports, eye, k, std::span<const HandPose>(&hand, 1), st, kTight);
  ASSERT_TRUE(finite_state(st));
  const Vec3 local = st.rotation.conjugate() * (st.tools[0].tip_mm - eye.globe_centre_mm) +
                     eye.globe_centre_mm - eye.lens_centre_mm;
  const double c = local.z() >= 0 ? eye.lens_anterior_mm : eye.lens_posterior_mm;
  const double f = std::sqrt((local.x() * local.x() + local.y() * local.y()) /
                                 (eye.lens_equator_radius_mm * eye.lens_equator_radius_mm) +
                             local.z() * local.z() / (c * c));
  EXPECT_GT(f, 1.0 - 1e-3) << "tip " << st.tools[0].tip_mm.transpose();
  EXPECT_GT(st.tools[0].tip_mm.z(), tip.z() + 0.5);  // pushed out, mostly upward
  // The phaco probe works inside the lens: without its lens spring the tip stays where the hand is.
  HandPose probe = hand;
  probe.lens_spring = false;
  GlobeState free_st;
  solve(ports, eye, k, std::span<const HandPose>(&probe, 1), free_st, kTight);
  EXPECT_LT((free_st.tools[0].tip_mm - tip).norm(), 0.05);
}

TEST(ToolEye, InnerCorneaSpringIsOneSided) {
  Stiffness k = standard();
  k.cornea_mn_mm = 1e7, k.tunnel_rot_mn_mm_rad = 0;
  const std::vector<EyePort> ports = {test_port()};
  const EyePort& p = ports[0];
  const EyeShape eye = test_eye();
  // Inside the posterior sphere: no cornea force, the tool stays on its hand pose.
  {
    const HandPose hand{p.centre_mm + 3.0 * p.axis, -p.axis, 0};
    ASSERT_LT((hand.tip_mm - eye.cornea_centre_mm).norm(), eye.cornea_posterior_radius_mm);
    GlobeState st;
    solve(ports, eye, k, std::span<const HandPose>(&hand, 1), st, kTight);
    EXPECT_LT((st.tools[0].tip_mm - hand.tip_mm).norm(), 1e-12);
  }
  // Beyond it (pressing the endothelium near the apex): pulled back to the surface, not further.
  {
    const Vec3 tip(3.0, 0.0, 5.0);
    const double out = (tip - eye.cornea_centre_mm).norm() - eye.cornea_posterior_radius_mm;
    ASSERT_GT(out, 0.5);
    const HandPose hand{tip, (p.centre_mm - tip).normalized(), 0};
    GlobeState st;
    solve(ports, eye, k, std::span<const HandPose>(&hand, 1), st, kTight);
    ASSERT_TRUE(finite_state(st));
    const Vec3 centre =
        eye.globe_centre_mm + st.rotation * (eye.cornea_centre_mm - eye.globe_centre_mm);
    const double after = (st.tools[0].tip_mm - centre).norm() - eye.cornea_posterior_radius_mm;
    EXPECT_LT(after, 1e-3);
    EXPECT_GT(after, -1e-3);  // one-sided: it does not push the tip on inward
  }
}

TEST(ToolEye, DegenerateInputsStayFinite) {
  const std::vector<EyePort> ports = {test_port(), side_port()};
  const EyeShape eye = test_eye();
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const Vec3 inside = ports[0].centre_mm + 1.5 * ports[0].axis;
  // Zero and NaN shafts, NaN tips: in no port.
  EXPECT_EQ(engaged_port(ports, Quat::Identity(), eye.globe_centre_mm, inside, Vec3::Zero(), -1),
            -1);
  EXPECT_EQ(
      engaged_port(ports, Quat::Identity(), eye.globe_centre_mm, inside, Vec3(nan, 0.0, 1.0), -1),
      -1);
  EXPECT_EQ(engaged_port(ports, Quat::Identity(), eye.globe_centre_mm, Vec3(nan, 0, 0),
                         -ports[0].axis, -1),
            -1);
  // A tool far from every port, and one pointing into the eye through the port: not engaged.
  EXPECT_EQ(engaged_port(ports, Quat::Identity(), eye.globe_centre_mm, Vec3(0, 0, 3.5),
                         Vec3::UnitZ(), -1),
            -1);
  EXPECT_EQ(engaged_port(ports, Quat::Identity(), eye.globe_centre_mm, inside, ports[0].axis, -1),
            -1);

  // Forced into a port anyway: zero shaft, NaN tip, the shaft parallel to the port plane, the tip
  // at the lens centre, the shaft exactly reversed; and three hands (the third is ignored).
  const std::vector<std::array<HandPose, 3>> cases = {
      {HandPose{inside, Vec3::Zero(), 0}, HandPose{inside, Vec3(nan, 0, 0), 1},
       HandPose{inside, -ports[0].axis, 0}},
      {HandPose{Vec3(nan, nan, nan), -ports[0].axis, 0},
       HandPose{ports[0].centre_mm, Vec3::UnitY(), 0}, HandPose{}},
      {HandPose{Vec3::Zero(), -ports[0].axis, 0}, HandPose{inside, ports[0].axis, 0}, HandPose{}},
      {HandPose{eye.globe_centre_mm, Vec3::UnitZ(), 1}, HandPose{inside, Vec3(1e-300, 0, 0), 0},
       HandPose{}}};
  for (const auto& hands : cases) {
    GlobeState st;
    solve(ports, eye, standard(), hands, st);
    EXPECT_TRUE(finite_state(st));
    solve(ports, eye, standard(), hands, st);  // warm start from it
    EXPECT_TRUE(finite_state(st));
  }
  // A state that went bad (e.g. memory from a bad frame) is reset, not propagated.
  GlobeState bad;
  bad.rotation.coeffs().setConstant(nan);
  bad.tools[0].tip_offset_mm = Vec3(nan, 0, 0);
  const HandPose hand{inside, -ports[0].axis, 0};
  solve(ports, eye, standard(), std::span<const HandPose>(&hand, 1), bad);
  EXPECT_TRUE(finite_state(bad));
}

TEST(ToolEye, WarmStartIsAlreadyConverged) {
  const std::vector<EyePort> ports = {test_port()};
  const EyePort& p = ports[0];
  const Vec3 tip = p.centre_mm + 2.0 * p.axis + Vec3(0.0, 1.5, -0.3);
  const HandPose hand{tip, (p.centre_mm + Vec3(0, 0.2, 0.3) - tip).normalized(), 0};
  GlobeState st;
  solve(ports, test_eye(), standard(), std::span<const HandPose>(&hand, 1), st, kTight);
  EXPECT_GT(rotation_vector(st.rotation).norm(), 1e-4);
  EXPECT_GE(st.iterations, 1);
  const Quat first = st.rotation;
  solve(ports, test_eye(), standard(), std::span<const HandPose>(&hand, 1), st, kTight);
  EXPECT_LE(st.iterations, 1);
  EXPECT_LT(rotation_vector(first.conjugate() * st.rotation).norm(), 1e-9);
}

TEST(ToolEye, PortHoldsItsToolUntilTheTipLeavesTheTunnel) {
  const std::vector<EyePort> ports = {test_port()};
  const EyePort& p = ports[0];
  const Vec3 gc = test_eye().globe_centre_mm;
  // Pushed well beyond the capture width: still in the port it was in.
  const Vec3 tip = p.centre_mm + 1.0 * p.axis + Vec3(0.0, 0.0, -3.0);
  EXPECT_EQ(engaged_port(ports, Quat::Identity(), gc, tip, -p.axis, -1), -1);
  EXPECT_EQ(engaged_port(ports, Quat::Identity(), gc, tip, -p.axis, 0), 0);
  // Withdrawn behind the outer opening: free.
  EXPECT_EQ(engaged_port(ports, Quat::Identity(), gc, p.centre_mm - 1.0 * p.axis, -p.axis, 0), -1);
}

}  // namespace
}  // namespace phaco::tool_eye
