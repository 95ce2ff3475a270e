#include "systems/tool_eye/tool_eye.hpp"

#include <algorithm>
#include <cmath>

namespace phaco::tool_eye {

namespace {

using Row = Vector;  // one residual's Jacobian over the 15 unknowns

constexpr int kGlobe = 6 * static_cast<int>(kMaxPortTools);
static_assert(kMaxPortTools == 2, "Unknowns::turn lists one identity per tool slot");

bool finite(const Vec3& v) {
  return std::isfinite(v.x()) && std::isfinite(v.y()) && std::isfinite(v.z());
}

Quat exp_rotation(const Vec3& v) {
  const double angle = v.norm();
  if (!(angle > 0.0)) return Quat::Identity();
  return Quat(Eigen::AngleAxisd(angle, v / angle));
}

// Everything the energy needs, shared by the evaluation and the line search.
struct Problem {
  std::span<const EyePort> ports;
  const EyeShape& eye;
  const Stiffness& k;
  std::span<const HandPose> hands;
};

// The unknowns as stored in GlobeState: tip offsets, shaft turns, globe rotation.
struct Unknowns {
  std::array<Vec3, kMaxPortTools> u{};
  std::array<Quat, kMaxPortTools> turn{Quat::Identity(), Quat::Identity()};  // kMaxPortTools
  Quat globe = Quat::Identity();
};

Unknowns unknowns_of(const GlobeState& s) {
  Unknowns x;
  for (uint32_t i = 0; i < kMaxPortTools; ++i) {
    x.u[i] = s.tools[i].tip_offset_mm;
    x.turn[i] = s.tools[i].shaft_turn;
  }
  x.globe = s.rotation;
  return x;
}

Unknowns stepped(const Unknowns& x, const Vector& d, double alpha) {
  Unknowns y = x;
  for (uint32_t i = 0; i < kMaxPortTools; ++i) {
    y.u[i] += alpha * d.segment<3>(6 * i);
    y.turn[i] = (exp_rotation(alpha * d.segment<3>(6 * i + 3)) * x.turn[i]).normalized();
  }
  y.globe = (exp_rotation(alpha * d.segment<3>(kGlobe)) * x.globe).normalized();
  return y;
}

// Per-tool outputs of one evaluation.
struct ToolOut {
  Vec3 port_force = Vec3::Zero(), port_moment = Vec3::Zero();
  double energy = 0;
};

// One spring: adds ½k·r² to the energy and, when asked, k·r·J to the gradient and k·J·Jᵀ to the
// Gauss–Newton Hessian.
void add_spring(double k, double r, const Row& j, double& energy, Matrix* h, Vector* g,
                double& tool_energy) {
  const double e = 0.5 * k * r * r;
  energy += e, tool_energy += e;
  if (g) *g += (k * r) * j;
  if (h) h->noalias() += k * (j * j.transpose());
}

// E at x; with h/g, its Gauss–Newton model. `out` (optional) receives each tool's port load.
double evaluate(const Problem& pb, const Unknowns& x, Matrix* h, Vector* g,
                std::array<ToolOut, kMaxPortTools>* out) {
  const Stiffness& k = pb.k;
  const EyeShape& eye = pb.eye;
  if (h) h->setZero();
  if (g) g->setZero();
  std::array<ToolOut, kMaxPortTools> local{};
  double energy = 0.0;

  const Eigen::Matrix3d rot = x.globe.toRotationMatrix();
  const Vec3& gc = eye.globe_centre_mm;
  const Vec3 theta = rotation_vector(x.globe);
  energy += 0.5 * k.globe_rot_mn_mm_rad * theta.squaredNorm();
  if (g) g->segment<3>(kGlobe) += k.globe_rot_mn_mm_rad * theta;
  if (h) h->diagonal().segment<3>(kGlobe).array() += k.globe_rot_mn_mm_rad;

  const uint32_t n = std::min<uint32_t>(kMaxPortTools, static_cast<uint32_t>(pb.hands.size()));
  for (uint32_t i = 0; i < kMaxPortTools; ++i) {
    const int ui = 6 * static_cast<int>(i), ei = ui + 3;
    // The hand's pull (every slot, so a free tool relaxes onto its hand pose).
    const Vec3 phi = rotation_vector(x.turn[i]);
    energy +=
        0.5 * k.hand_mn_mm * x.u[i].squaredNorm() + 0.5 * k.hand_rot_mn_mm_rad * phi.squaredNorm();
    if (g) {
      g->segment<3>(ui) += k.hand_mn_mm * x.u[i];
      g->segment<3>(ei) += k.hand_rot_mn_mm_rad * phi;
    }
    if (h) {
      h->diagonal().segment<3>(ui).array() += k.hand_mn_mm;
      h->diagonal().segment<3>(ei).array() += k.hand_rot_mn_mm_rad;
    }
    if (i >= n) continue;
    const HandPose& hand = pb.hands[i];
    if (hand.port < 0 || static_cast<size_t>(hand.port) >= pb.ports.size()) continue;
    const EyePort& port = pb.ports[static_cast<size_t>(hand.port)];
    const double shaft_len = hand.shaft.norm();
    if (!(shaft_len > 1e-12) || !finite(hand.tip_mm)) continue;

    double& te = local[i].energy;
    const Vec3 p = hand.tip_mm + x.u[i];
    const Vec3 d = (x.turn[i] * (hand.shaft / shaft_len)).normalized();
    // The shaft's axis passes through pa, beside the tip by the bent point turned with the tool.
    const bool bent = !hand.axis_offset_mm.isZero();
    const Vec3 o = bent ? Vec3(x.turn[i] * hand.axis_offset_mm) : Vec3::Zero();
    const Vec3 pa = bent ? Vec3(p + o) : p;
    const Vec3 rc = rot * (port.centre_mm - gc);  // port centre from the globe centre
    const Vec3 c = gc + rc;
    const Vec3 a = rot * port.axis;
    const Vec3 ew = rot * port.width_dir;
    const Vec3 eh = a.cross(ew);

    // Tunnel, translational: the shaft's axis's offset from the port centre.
    const Vec3 w = c - pa;
    const double s = w.dot(d);
    const Vec3 delta = w - s * d;
    const double half_width = 0.5 * port.width_mm;
    for (int axis = 0; axis < 2; ++axis) {
      const Vec3& e = axis == 0 ? ew : eh;
      const double free = axis == 0 ? half_width : 0.0;
      const double de = delta.dot(e);
      if (std::abs(de) <= free) continue;
      const double r = de - std::copysign(free, de);
      const Vec3 ge = e - d.dot(e) * d;  // ∂δ_e/∂w
      Row j = Row::Zero();
      j.segment<3>(ui) = -ge;
      j.segment<3>(ei) = -d.dot(e) * d.cross(w) - s * d.cross(e);
      if (bent) j.segment<3>(ei) -= o.cross(ge);  // the axis point swings about the tip too
      j.segment<3>(kGlobe) = rc.cross(ge) + e.cross(delta);
      add_spring(k.tunnel_mn_mm, r, j, energy, h, g, te);
      local[i].port_force += -k.tunnel_mn_mm * r * ge;
    }

    // Tunnel, rotational: the shaft's angle β from the tunnel axis (d = −a when aligned).
    const Vec3 m = d.cross(a);
    const double sin_b = m.norm();
    const double beta = std::atan2(sin_b, -d.dot(a));
    if (beta > k.tunnel_free_angle_rad && sin_b > 1e-12) {
      const Vec3 mh = m / sin_b;
      Row j = Row::Zero();
      j.segment<3>(ei) = mh;
      j.segment<3>(kGlobe) = -mh;
      const double r = beta - k.tunnel_free_angle_rad;
      add_spring(k.tunnel_rot_mn_mm_rad, r, j, energy, h, g, te);
      local[i].port_moment += k.tunnel_rot_mn_mm_rad * r * mh;
    }

    // Inner cornea surface: once the tip is past the tunnel's inner opening it stays inside the
    // posterior corneal sphere (one-sided).
    if ((p - c).dot(a) > 0.5 * port.tunnel_length_mm) {
      const Vec3 rs = rot * (eye.cornea_centre_mm - gc);
      const Vec3 v = p - (gc + rs);
      const double dist = v.norm();
      if (dist > eye.cornea_posterior_radius_mm && dist > 1e-12) {
        const Vec3 nrm = v / dist;
        Row j = Row::Zero();
        j.segment<3>(ui) = nrm;
        j.segment<3>(kGlobe) = -rs.cross(nrm);
        add_spring(k.cornea_mn_mm, dist - eye.cornea_posterior_radius_mm, j, energy, h, g, te);
      }
    }

    // Lens: the tip outside the two half-ellipsoids, pushed out radially from the lens centre
    // (seed 001's "unidirectional radial interaction"), in the globe's turned frame.
    if (hand.lens_spring) {
      const Vec3 pg = p - gc;
      const Vec3 q = rot.transpose() * pg + gc - eye.lens_centre_mm;
      const double qn = q.norm();
      const double ea = eye.lens_equator_radius_mm;
      const double ec = q.z() >= 0.0 ? eye.lens_anterior_mm : eye.lens_posterior_mm;
      if (qn > 1e-9 && ea > 0.0 && ec > 0.0) {
        const double f =
            std::sqrt((q.x() * q.x() + q.y() * q.y()) / (ea * ea) + (q.z() * q.z()) / (ec * ec));
        if (f < 1.0 && f > 1e-12) {
          const double depth = qn * (1.0 / f - 1.0);  // along the ray from the centre
          const Vec3 grad_f = Vec3(q.x() / (ea * ea), q.y() / (ea * ea), q.z() / (ec * ec)) / f;
          const Vec3 grad_local = (q / qn) * (1.0 / f - 1.0) - (qn / (f * f)) * grad_f;
          const Vec3 gw = rot * grad_local;
          Row j = Row::Zero();
          j.segment<3>(ui) = gw;
          j.segment<3>(kGlobe) = -pg.cross(gw);
          add_spring(k.lens_mn_mm, depth, j, energy, h, g, te);
        }
      }
    }
  }
  if (out) *out = local;
  return energy;
}

bool finite_unknowns(const Unknowns& x) {
  for (uint32_t i = 0; i < kMaxPortTools; ++i) {
    if (!finite(x.u[i]) || !x.turn[i].coeffs().allFinite()) return false;
  }
  return x.globe.coeffs().allFinite();
}

}  // namespace

Vec3 rotation_vector(const Quat& q_in) {
  Quat q = q_in;
  if (q.w() < 0.0) q.coeffs() = -q.coeffs();  // the same rotation, angle ≤ π
  const double s = q.vec().norm();
  if (!(s > 0.0)) return Vec3::Zero();
  const double angle = 2.0 * std::atan2(s, q.w());
  return (angle / s) * q.vec();
}

int engaged_port(std::span<const EyePort> ports, const Quat& globe_rotation,
                 const Vec3& globe_centre, const Vec3& tip_mm, const Vec3& shaft, int current,
                 const Vec3& axis_offset_mm) {
  const double len = shaft.norm();
  if (!(len > 1e-12) || !finite(tip_mm) || !std::isfinite(len)) return -1;
  const Vec3 on_axis = finite(axis_offset_mm) ? Vec3(tip_mm + axis_offset_mm) : tip_mm;
  const Vec3 d = shaft / len;
  const Eigen::Matrix3d rot = globe_rotation.normalized().toRotationMatrix();
  int best = -1;
  double best_offset = 0;
  for (size_t j = 0; j < ports.size(); ++j) {
    const EyePort& port = ports[j];
    const Vec3 c = globe_centre + rot * (port.centre_mm - globe_centre);
    const Vec3 a = rot * port.axis;
    const double depth = (tip_mm - c).dot(a);  // the tip's way along the tunnel
    const double s = (c - on_axis).dot(d);     // where the shaft passes the centre
    const double offset = ((c - on_axis) - s * d).norm();
    if (static_cast<int>(j) == current) {
      // Held until the tip is back out of the tunnel.
      if (depth > -0.5 * port.tunnel_length_mm && s > 0.0) return current;
      continue;
    }
    const bool inserted = depth > -0.5 * port.tunnel_length_mm && s > 0.0 && d.dot(a) < 0.0;
    if (inserted && offset < port.width_mm && (best < 0 || offset < best_offset)) {
      best = static_cast<int>(j), best_offset = offset;
    }
  }
  return best;
}

int conjugate_gradient(const Matrix& h, const Vector& b, Vector& x, int max_iterations,
                       double tolerance) {
  Vector inv_diag;
  for (int i = 0; i < kUnknowns; ++i) {
    inv_diag[i] = h(i, i) > 0.0 ? 1.0 / h(i, i) : 1.0;
  }
  Vector r = b - h * x;
  Vector z = inv_diag.cwiseProduct(r);
  Vector p = z;
  double rz = r.dot(z);
  const double b_norm = std::max(b.norm(), 1e-300);
  int it = 0;
  for (; it < max_iterations; ++it) {
    if (r.norm() <= tolerance * b_norm) break;
    const Vector hp = h * p;
    const double php = p.dot(hp);
    if (!(php > 0.0)) break;  // not SPD along p (never with k > 0): keep what we have
    const double alpha = rz / php;
    x += alpha * p;
    r -= alpha * hp;
    z = inv_diag.cwiseProduct(r);
    const double rz_next = r.dot(z);
    p = z + (rz_next / rz) * p;
    rz = rz_next;
  }
  return it;
}

Quadratic linearise(std::span<const EyePort> ports, const EyeShape& eye, const Stiffness& k,
                    std::span<const HandPose> hands, const GlobeState& state) {
  Quadratic q;
  const Problem pb{ports, eye, k, hands};
  q.energy = evaluate(pb, unknowns_of(state), &q.hessian, &q.gradient, nullptr);
  return q;
}

void solve(std::span<const EyePort> ports, const EyeShape& eye, const Stiffness& k,
           std::span<const HandPose> hands, GlobeState& state, const SolverOptions& options) {
  const Problem pb{ports, eye, k, hands};
  Unknowns x = unknowns_of(state);
  if (!finite_unknowns(x)) x = Unknowns{};
  Matrix h;
  Vector g;
  int steps = 0, cg = 0;
  double energy = evaluate(pb, x, &h, &g, nullptr);
  for (; steps < options.max_steps; ++steps) {
    if (!(g.lpNorm<Eigen::Infinity>() > options.gradient_tol)) break;
    Vector dx = Vector::Zero();
    cg += conjugate_gradient(h, -g, dx, options.max_cg, 1e-12);
    // Backtrack: a one-sided spring switching on or off makes the model optimistic. Near the
    // minimum the decrease falls below E's rounding (δ comes from differences of mm-sized
    // positions); there a full step that shrinks the gradient is taken as descent.
    Matrix h_trial;
    Vector g_trial;
    Unknowns trial = stepped(x, dx, 1.0);
    double e_trial = evaluate(pb, trial, &h_trial, &g_trial, nullptr);
    double alpha = 1.0;
    const double noise = 1e-10 * std::abs(energy);
    const bool flat = e_trial <= energy + noise && g_trial.squaredNorm() < g.squaredNorm();
    for (int b = 0; b < 8 && !flat && !(e_trial <= energy); ++b) {
      alpha *= 0.5;
      trial = stepped(x, dx, alpha);
      e_trial = evaluate(pb, trial, &h_trial, &g_trial, nullptr);
    }
    if (!flat && !(e_trial <= energy)) break;  // no descent left at this precision
    x = trial;
    energy = e_trial, h = h_trial, g = g_trial;
    if (alpha * dx.lpNorm<Eigen::Infinity>() < 1e-13) break;
  }
  std::array<ToolOut, kMaxPortTools> out{};
  energy = evaluate(pb, x, nullptr, nullptr, &out);
  if (!finite_unknowns(x) || !std::isfinite(energy)) {
    x = Unknowns{};  // fail safe: the hands' poses, the globe at rest
    energy = 0, out = {};
  }

  state.rotation = x.globe;
  state.energy_mn_mm = energy;
  state.iterations = steps;
  state.cg_iterations = cg;
  for (uint32_t i = 0; i < kMaxPortTools; ++i) {
    ToolPortState& t = state.tools[i];
    t.tip_offset_mm = x.u[i];
    t.shaft_turn = x.turn[i];
    t.port_force_mn = out[i].port_force;
    t.port_moment_mn_mm = out[i].port_moment;
    t.energy_mn_mm = out[i].energy;
    if (i < hands.size()) {
      const HandPose& hand = hands[i];
      const double len = hand.shaft.norm();
      const bool tip_ok = finite(hand.tip_mm), shaft_ok = len > 1e-12 && std::isfinite(len);
      // A hand with no usable pose is in no port; what is shown stays finite (the origin, +z).
      t.port = tip_ok && shaft_ok ? hand.port : -1;
      t.tip_mm = tip_ok ? Vec3(hand.tip_mm + x.u[i]) : Vec3::Zero();
      t.shaft = shaft_ok ? Vec3((x.turn[i] * (hand.shaft / len)).normalized()) : Vec3::UnitZ();
    } else {
      t = ToolPortState{};
    }
  }
}

}  // namespace phaco::tool_eye
