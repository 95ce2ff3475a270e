#include <algorithm>
#include <array>
#include <numeric>

#include "systems/sculpt/broadphase.hpp"

namespace phaco::sculpt {

const char* to_string(Broadphase broadphase) {
  return broadphase == Broadphase::Octree ? "octree" : "dbvt";
}

namespace {

constexpr uint32_t kMaxOctreeDepth = 16;

struct Builder {
  const TetTopology& topo;
  TetOctree& tree;
  std::vector<uint32_t> scratch;

  // Fills node `index` from ids[begin, end) inside the cube (centre c, half size h).
  void build(uint32_t index, std::vector<uint32_t>& ids, uint32_t begin, uint32_t end,
             const std::array<double, 3>& c, double h, uint32_t depth) {
    tree.depth = std::max(tree.depth, depth);
    OctreeNode node;
    for (int a = 0; a < 3; ++a) node.lo[a] = 1e30f, node.hi[a] = -1e30f;
    for (uint32_t i = begin; i < end; ++i) {
      const uint32_t t = ids[i];
      const float p[3] = {topo.centre_x[t], topo.centre_y[t], topo.centre_z[t]};
      const float r = topo.bound_radius[t] * 1.00001f + 1e-5f;  // float rounding margin
      for (int a = 0; a < 3; ++a) {
        node.lo[a] = std::min(node.lo[a], p[a] - r);
        node.hi[a] = std::max(node.hi[a], p[a] + r);
      }
    }
    if (end - begin <= tree.leaf_capacity || depth >= kMaxOctreeDepth) {
      node.leaf = true;
      node.first = static_cast<uint32_t>(tree.items.size());
      node.count = end - begin;
      std::stable_sort(ids.begin() + begin, ids.begin() + end,
                       [&](uint32_t x, uint32_t y) { return topo.centre_z[x] > topo.centre_z[y]; });
      for (uint32_t i = begin; i < end; ++i) {
        tree.items.push_back(ids[i]);
        tree.item_z.push_back(topo.centre_z[ids[i]]);
        node.max_bound = std::max(node.max_bound, topo.bound_radius[ids[i]]);
      }
      tree.nodes[index] = node;
      return;
    }
    // Stable partition into the eight octants (bit 0: x, 1: y, 2: z above the centre).
    std::array<uint32_t, 9> offset{};
    auto octant = [&](uint32_t t) {
      return (topo.centre_x[t] >= c[0] ? 1 : 0) | (topo.centre_y[t] >= c[1] ? 2 : 0) |
             (topo.centre_z[t] >= c[2] ? 4 : 0);
    };
    for (uint32_t i = begin; i < end; ++i) ++offset[octant(ids[i]) + 1];
    for (int o = 0; o < 8; ++o) offset[o + 1] += offset[o];
    scratch.resize(end - begin);
    std::array<uint32_t, 8> fill{};
    for (uint32_t i = begin; i < end; ++i) {
      const int o = octant(ids[i]);
      scratch[offset[o] + fill[o]++] = ids[i];
    }
    std::copy(scratch.begin(), scratch.end(), ids.begin() + begin);

    uint32_t children = 0;
    for (int o = 0; o < 8; ++o) children += offset[o + 1] > offset[o] ? 1 : 0;
    node.first = static_cast<uint32_t>(tree.nodes.size());
    node.count = children;
    tree.nodes[index] = node;
    tree.nodes.resize(tree.nodes.size() + children);
    uint32_t child = node.first;
    for (int o = 0; o < 8; ++o) {
      if (offset[o + 1] == offset[o]) continue;
      const double q = 0.5 * h;
      const std::array<double, 3> cc = {c[0] + ((o & 1) ? q : -q), c[1] + ((o & 2) ? q : -q),
                                        c[2] + ((o & 4) ? q : -q)};
      build(child++, ids, begin + offset[o], begin + offset[o + 1], cc, q, depth + 1);
    }
  }
};

bool boxes_overlap(const float lo[3], const float hi[3], const Vec3& qlo, const Vec3& qhi) {
  for (int a = 0; a < 3; ++a)
    if (hi[a] < qlo[a] || lo[a] > qhi[a]) return false;
  return true;
}

}  // namespace

TetOctree build_tet_octree(const TetTopology& topo, uint32_t leaf_capacity) {
  TetOctree tree;
  tree.leaf_capacity = std::max<uint32_t>(leaf_capacity, 1);
  const uint32_t n = topo.tet_count;
  std::vector<uint32_t> ids(n);
  std::iota(ids.begin(), ids.end(), 0u);
  Vec3 lo = Vec3::Constant(1e30), hi = Vec3::Constant(-1e30);
  for (uint32_t t = 0; t < n; ++t) {
    const Vec3 p = tet_centre(topo, t);
    lo = lo.cwiseMin(p), hi = hi.cwiseMax(p);
  }
  if (n == 0) lo = hi = Vec3::Zero();
  const Vec3 c = 0.5 * (lo + hi);
  const double h = 0.5 * (hi - lo).maxCoeff() * (1.0 + 1e-9) + 1e-9;
  tree.nodes.resize(1);
  tree.items.reserve(n);
  tree.item_z.reserve(n);
  Builder builder{topo, tree, {}};
  builder.build(0, ids, 0, n, {c.x(), c.y(), c.z()}, h, 0);
  return tree;
}

void octree_candidates(const TetOctree& tree, const TetTopology& topo, const TipCapsule& tip,
                       std::vector<uint32_t>& queue, std::vector<uint32_t>& out,
                       BroadphaseStats& stats) {
  if (tree.nodes.empty() || tree.items.empty()) return;
  const Vec3 qlo = tip.a.cwiseMin(tip.b) - Vec3::Constant(tip.radius);
  const Vec3 qhi = tip.a.cwiseMax(tip.b) + Vec3::Constant(tip.radius);
  queue.clear();
  queue.push_back(0);
  for (size_t head = 0; head < queue.size(); ++head) {
    const OctreeNode& node = tree.nodes[queue[head]];
    ++stats.nodes_visited;
    if (!boxes_overlap(node.lo, node.hi, qlo, qhi)) continue;
    if (!node.leaf) {
      for (uint32_t k = 0; k < node.count; ++k) queue.push_back(node.first + k);
      continue;
    }
    // Entries run from the viewer (+z) backward: skip those above the window, stop below it.
    const double z_top = qhi.z() + node.max_bound + 1e-5,
                 z_bottom = qlo.z() - node.max_bound - 1e-5;
    for (uint32_t i = node.first, e = node.first + node.count; i < e; ++i) {
      const double z = tree.item_z[i];
      if (z > z_top) continue;
      if (z < z_bottom) break;
      ++stats.tets_scanned;
      const uint32_t t = tree.items[i];
      if (topo.alive[t] && bound_touches_tip(topo, t, tip)) out.push_back(t);
    }
  }
}

}  // namespace phaco::sculpt
