// Bins kept current by re-binning only what moved answer nearest-particle queries exactly as a
// scan of every particle does (systems/point_bins).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <vector>

#include "engine/core/table.hpp"
#include "systems/point_bins/point_bins.hpp"

namespace phaco {
namespace {

uint32_t scan_nearest(const Particles& p, const Vec3& q, double r) {
  uint32_t best_i = point_bins::kNoParticle;
  double best = r * r;
  for (uint32_t i = 0; i < p.slots.size(); ++i) {
    if (!p.slots.alive(i)) continue;
    const double dx = p.x[i] - q.x(), dy = p.y[i] - q.y(), dz = p.z[i] - q.z();
    const double d2 = dx * dx + dy * dy + dz * dz;
    if (d2 < best || (d2 == best && i < best_i)) best = d2, best_i = i;
  }
  return best_i;
}

uint32_t add_particle(Particles& p, float x, float y, float z) {
  const uint32_t i = table_add(p);
  p.x[i] = x, p.y[i] = y, p.z[i] = z;
  return i;
}

TEST(PointBins, MovedAddedAndRemovedParticlesAnswerAsAScan) {
  std::mt19937 rng(17);
  std::uniform_real_distribution<float> u(-4.0f, 4.0f);
  Particles p;
  for (int i = 0; i < 3000; ++i) add_particle(p, u(rng), u(rng), 0.2f * u(rng));
  point_bins::PointBins bins;
  point_bins::bin_all(bins, p, 0.5);
  std::vector<uint32_t> moved;
  int found = 0;
  for (int round = 0; round < 40; ++round) {
    // Some particles move (the "active set"), some are removed, some appended or put in freed
    // slots.
    moved.clear();
    for (int k = 0; k < 150; ++k) {
      const uint32_t i = static_cast<uint32_t>(rng() % p.slots.size());
      if (!p.slots.alive(i)) continue;
      p.x[i] += 0.3f * u(rng), p.y[i] += 0.3f * u(rng), p.z[i] += 0.05f * u(rng);
      moved.push_back(i);
    }
    for (int k = 0; k < 10; ++k) {
      const uint32_t i = static_cast<uint32_t>(rng() % p.slots.size());
      if (p.slots.alive(i)) table_remove(p, i);
    }
    for (int k = 0; k < 20; ++k) {
      const uint32_t i = add_particle(p, u(rng), u(rng), 0.2f * u(rng));
      // A reused slot is not past the binned count: the caller lists it as moved (new particles
      // seed the capsule's active set).
      if (i < bins.key_of.size()) moved.push_back(i);
    }
    point_bins::rebin(bins, p, moved);
    point_bins::bin_appended(bins, p);
    for (int q = 0; q < 50; ++q) {
      const Vec3 at(u(rng), u(rng), 0.2 * u(rng));
      const double r = 0.05 + 0.5 * (q % 4);
      const uint32_t want = scan_nearest(p, at, r);
      EXPECT_EQ(point_bins::nearest(bins, p, at, r), want) << "round " << round << " query " << q;
      found += want != point_bins::kNoParticle;
    }
  }
  EXPECT_GT(found, 500) << "most queries find a particle";
}

TEST(PointBins, NothingWithinTheRadiusOrANonFinitePointFindsNothing) {
  Particles p;
  add_particle(p, 0.0f, 0.0f, 0.0f);
  point_bins::PointBins bins;
  point_bins::bin_all(bins, p, 0.25);
  EXPECT_EQ(point_bins::nearest(bins, p, Vec3(0.0, 0.0, 0.0), 0.0), 0u);
  EXPECT_EQ(point_bins::nearest(bins, p, Vec3(1.0, 0.0, 0.0), 0.9), point_bins::kNoParticle);
  EXPECT_EQ(point_bins::nearest(bins, p, Vec3(std::nan(""), 0.0, 0.0), 1.0),
            point_bins::kNoParticle);
  EXPECT_EQ(point_bins::nearest(bins, p, Vec3(1.0, 0.0, 0.0), 1.0), 0u);
}

}  // namespace
}  // namespace phaco
