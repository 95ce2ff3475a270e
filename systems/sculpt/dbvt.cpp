// btDbvt over the tets' bounding-sphere boxes. Leaves carry the tet index in dataAsInt.
#include <BulletCollision/BroadphaseCollision/btDbvt.h>

#include "systems/sculpt/broadphase.hpp"

namespace phaco::sculpt {

struct TetDbvt::Impl {
  btDbvt tree;
  std::vector<btDbvtNode*> leaf;  // per tet; nullptr once removed
  mutable btNodeStack stack;      // collideTV scratch, reused between queries
};

TetDbvt::TetDbvt() = default;
TetDbvt::~TetDbvt() = default;
TetDbvt::TetDbvt(TetDbvt&&) noexcept = default;
TetDbvt& TetDbvt::operator=(TetDbvt&&) noexcept = default;

void TetDbvt::build(const TetTopology& topo) {
  impl_ = std::make_unique<Impl>();
  impl_->leaf.assign(topo.tet_count, nullptr);
  for (uint32_t t = 0; t < topo.tet_count; ++t) {
    if (!topo.alive[t]) continue;
    // Inflated a little so float rounding never drops a tet the double-precision filter keeps.
    const float r = topo.bound_radius[t] * 1.00001f + 1e-5f;
    const btVector3 c(topo.centre_x[t], topo.centre_y[t], topo.centre_z[t]);
    const btDbvtVolume box = btDbvtVolume::FromCR(c, r);
    btDbvtNode* node = impl_->tree.insert(box, nullptr);
    node->dataAsInt = static_cast<int>(t);
    impl_->leaf[t] = node;
  }
  // Insertion order follows TetGen's numbering; a top-down rebuild gives a balanced tree and keeps
  // the leaf nodes (only internal nodes are recreated).
  impl_->tree.optimizeTopDown();
  impl_->stack.reserve(256);
}

void TetDbvt::remove(uint32_t tet) {
  if (!impl_ || tet >= impl_->leaf.size() || impl_->leaf[tet] == nullptr) return;
  impl_->tree.remove(impl_->leaf[tet]);
  impl_->leaf[tet] = nullptr;
}

namespace {

struct Collector : btDbvt::ICollide {
  const TetTopology* topo;
  const TipCapsule* tip;
  std::vector<uint32_t>* out;
  BroadphaseStats* stats;
  void Process(const btDbvtNode* leaf) override {
    ++stats->tets_scanned;
    const auto t = static_cast<uint32_t>(leaf->dataAsInt);
    if (topo->alive[t] && bound_touches_tip(*topo, t, *tip)) out->push_back(t);
  }
};

}  // namespace

void TetDbvt::candidates(const TetTopology& topo, const TipCapsule& tip, std::vector<uint32_t>& out,
                         BroadphaseStats& stats) const {
  if (!impl_ || impl_->tree.m_root == nullptr) return;
  const Vec3 lo = tip.a.cwiseMin(tip.b) - Vec3::Constant(tip.radius);
  const Vec3 hi = tip.a.cwiseMax(tip.b) + Vec3::Constant(tip.radius);
  const btDbvtVolume box =
      btDbvtVolume::FromMM(btVector3(lo.x(), lo.y(), lo.z()), btVector3(hi.x(), hi.y(), hi.z()));
  Collector collector;
  collector.topo = &topo;
  collector.tip = &tip;
  collector.out = &out;
  collector.stats = &stats;
  impl_->tree.collideTVNoStackAlloc(impl_->tree.m_root, box, impl_->stack, collector);
}

}  // namespace phaco::sculpt
