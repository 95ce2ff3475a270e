#include "perf/peers/bullet_membrane.hpp"

#include <BulletSoftBody/btSoftBody.h>
#include <BulletSoftBody/btSoftBodyRigidBodyCollisionConfiguration.h>
#include <BulletSoftBody/btSoftRigidDynamicsWorld.h>
#include <btBulletDynamicsCommon.h>

#include <algorithm>
#include <cmath>
#include <vector>

namespace phaco::perf {

struct BulletMembrane::Impl {
  btSoftBodyRigidBodyCollisionConfiguration config;
  btCollisionDispatcher dispatcher{&config};
  btDbvtBroadphase broadphase;
  btSequentialImpulseConstraintSolver solver;
  btSoftRigidDynamicsWorld world{&dispatcher, &broadphase, &solver, &config};
  btSoftBody* body = nullptr;
  double dt = 0;
  float klst = 1;
};

BulletMembrane::BulletMembrane(const Particles& p, const Triangles& tris, const Springs& s,
                               const BulletMembraneOptions& o)
    : impl_(std::make_unique<Impl>()) {
  Impl& m = *impl_;
  m.dt = o.dt_s;
  btSoftBodyWorldInfo& info = m.world.getWorldInfo();
  info.m_broadphase = &m.broadphase;
  info.m_dispatcher = &m.dispatcher;
  info.m_gravity.setValue(0, 0, 0);
  info.air_density = 0;
  info.water_density = 0;
  info.m_sparsesdf.Initialize();
  m.world.setGravity(btVector3(0, 0, 0));

  const uint32_t n = p.slots.size();
  std::vector<btVector3> x(n);
  std::vector<btScalar> mass(n);
  for (uint32_t v = 0; v < n; ++v) {
    x[v].setValue(p.x[v], p.y[v], p.z[v]);
    mass[v] = p.inv_mass[v] > 0 ? 1.0f / p.inv_mass[v] : 0.0f;
  }
  m.body = new btSoftBody(&info, static_cast<int>(n), x.data(), mass.data());

  // kLST from the median spring (see the header).
  std::vector<double> kw;
  for (uint32_t e = 0; e < s.slots.size(); ++e) {
    const double w = p.inv_mass[s.i[e]] + p.inv_mass[s.j[e]];
    if (w > 0) kw.push_back(s.stiffness[e] * w * o.dt_s * o.dt_s);
  }
  double median = 1.0;
  if (!kw.empty()) {
    std::nth_element(kw.begin(), kw.begin() + kw.size() / 2, kw.end());
    median = kw[kw.size() / 2];
  }
  m.klst = static_cast<float>(std::clamp(median / (1.0 + median), 1e-6, 1.0));
  btSoftBody::Material* mat = m.body->appendMaterial();
  mat->m_kLST = m.klst;
  mat->m_kAST = 0;
  mat->m_kVST = 0;
  for (uint32_t e = 0; e < s.slots.size(); ++e) {
    m.body->appendLink(static_cast<int>(s.i[e]), static_cast<int>(s.j[e]), mat, false);
  }
  for (uint32_t t = 0; t < tris.slots.size(); ++t) {
    m.body->appendFace(static_cast<int>(tris.a[t]), static_cast<int>(tris.b[t]),
                       static_cast<int>(tris.c[t]), mat);
  }
  m.body->m_cfg.piterations = std::max(1, o.position_iterations);
  m.body->m_cfg.kDP = static_cast<btScalar>(o.damping);
  m.body->m_cfg.collisions = 0;  // no rigid bodies, no self-collision: the membrane solve only
  // Compute the runtime constants now and clear the flag, or the first step would recompute them
  // and reset the rest lengths to the mesh lengths; then put in our rest lengths (pre-stretch).
  m.body->updateConstants();
  m.body->m_bUpdateRtCst = false;
  for (int e = 0; e < m.body->m_links.size(); ++e) {
    btSoftBody::Link& l = m.body->m_links[e];
    l.m_rl = s.rest_length[e];
    l.m_c1 = l.m_rl * l.m_rl;
  }
  // A soft body whose nodes barely move falls asleep and Bullet skips it; we time and compare a
  // body that is simulated every step.
  m.body->setActivationState(DISABLE_DEACTIVATION);
  m.world.addSoftBody(m.body);
}

BulletMembrane::~BulletMembrane() {
  if (impl_ && impl_->body) {
    impl_->world.removeSoftBody(impl_->body);
    delete impl_->body;
  }
}

void BulletMembrane::add_force(uint32_t node, float fx, float fy, float fz) {
  impl_->body->addForce(btVector3(fx, fy, fz), static_cast<int>(node));
}

void BulletMembrane::step() {
  impl_->world.stepSimulation(static_cast<btScalar>(impl_->dt), 0,
                              static_cast<btScalar>(impl_->dt));
}

uint32_t BulletMembrane::node_count() const {
  return static_cast<uint32_t>(impl_->body->m_nodes.size());
}

float BulletMembrane::link_stiffness() const {
  return impl_->klst;
}

void BulletMembrane::position(uint32_t node, float& x, float& y, float& z) const {
  const btVector3& v = impl_->body->m_nodes[static_cast<int>(node)].m_x;
  x = v.x(), y = v.y(), z = v.z();
}

bool BulletMembrane::finite() const {
  for (int i = 0; i < impl_->body->m_nodes.size(); ++i) {
    const btVector3& v = impl_->body->m_nodes[i].m_x;
    if (!std::isfinite(v.x()) || !std::isfinite(v.y()) || !std::isfinite(v.z())) return false;
  }
  return true;
}

double BulletMembrane::max_speed_mm_s() const {
  double best = 0;
  for (int i = 0; i < impl_->body->m_nodes.size(); ++i) {
    const double s = impl_->body->m_nodes[i].m_v.length();
    if (!std::isfinite(s)) return INFINITY;
    best = std::max(best, s);
  }
  return best;
}

}  // namespace phaco::perf
