// Poly6 kernel and the neighbour grid (systems/sph/kernel.hpp, grid.hpp, neighbours.hpp).
#include <gtest/gtest.h>
#include <oneapi/tbb/task_arena.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <numbers>
#include <random>
#include <string>
#include <vector>

#include "systems/sph/grid.hpp"
#include "systems/sph/kernel.hpp"
#include "systems/sph/neighbours.hpp"

namespace phaco::sph {
namespace {

constexpr CellOrder kOrders[] = {CellOrder::Morton, CellOrder::Linear, CellOrder::UnsortedHash};

struct Cloud {
  std::vector<float> x, y, z, m;
  uint32_t size() const { return static_cast<uint32_t>(x.size()); }
};

// Uniform in a box, plus a dense cluster, exact duplicates and points on cell boundaries.
Cloud random_cloud(uint32_t n, float box, uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(0.0f, box);
  std::normal_distribution<float> g(0.0f, 0.05f * box);
  Cloud c;
  for (uint32_t i = 0; i < n; ++i) {
    const bool cluster = i % 4 == 0;
    c.x.push_back(cluster ? 0.5f * box + g(rng) : u(rng));
    c.y.push_back(cluster ? 0.3f * box + g(rng) : u(rng));
    c.z.push_back(cluster ? 0.6f * box + g(rng) : u(rng) - 0.5f * box);
    c.m.push_back(0.5f + static_cast<float>(i % 7) * 0.1f);
  }
  for (uint32_t i = 0; i < n / 50; ++i) {  // duplicates
    c.x.push_back(c.x[i]);
    c.y.push_back(c.y[i]);
    c.z.push_back(c.z[i]);
    c.m.push_back(1.0f);
  }
  return c;
}

// Brute-force neighbour lists; pairs within 1e-5 relative of h are ambiguous under rounding and
// reported separately so the comparison can skip them.
void brute_force(const Cloud& c, float h, std::vector<std::vector<uint32_t>>& lists,
                 std::vector<std::vector<uint32_t>>& ambiguous) {
  const uint32_t n = c.size();
  lists.assign(n, {});
  ambiguous.assign(n, {});
  for (uint32_t i = 0; i < n; ++i)
    for (uint32_t j = 0; j < n; ++j) {
      if (i == j) continue;
      const double dx = double(c.x[i]) - c.x[j], dy = double(c.y[i]) - c.y[j],
                   dz = double(c.z[i]) - c.z[j];
      const double r = std::sqrt(dx * dx + dy * dy + dz * dz);
      if (std::abs(r - h) <= 1e-5 * h)
        ambiguous[i].push_back(j);
      else if (r < h)
        lists[i].push_back(j);
    }
}

std::vector<uint32_t> without(const std::vector<uint32_t>& a, const std::vector<uint32_t>& skip) {
  std::vector<uint32_t> out;
  for (uint32_t v : a)
    if (std::find(skip.begin(), skip.end(), v) == skip.end()) out.push_back(v);
  return out;
}

TEST(SphKernel, Poly6IntegratesToOneAndVanishesAtSupport) {
  for (double h : {0.05, 0.15, 1.0, 3.0}) {
    // Radial integral 4π ∫ W r² dr by Simpson's rule.
    const int steps = 2000;
    double sum = 0.0;
    for (int k = 0; k <= steps; ++k) {
      const double r = h * k / steps;
      const double w = (k == 0 || k == steps) ? 1.0 : (k % 2 ? 4.0 : 2.0);
      sum += w * poly6(r * r, h) * r * r;
    }
    const double integral = 4.0 * std::numbers::pi * sum * (h / steps) / 3.0;
    EXPECT_NEAR(integral, 1.0, 1e-9) << "h " << h;
    // A 3D lattice sum: ∑ W(|p|)·a³ over a lattice of spacing a = h/20.
    const double a = h / 20.0;
    double lattice = 0.0;
    for (int i = -20; i <= 20; ++i)
      for (int j = -20; j <= 20; ++j)
        for (int k = -20; k <= 20; ++k)
          lattice += poly6(a * a * (i * i + j * j + k * k), h) * a * a * a;
    EXPECT_NEAR(lattice, 1.0, 1e-3) << "h " << h;
    EXPECT_EQ(poly6(h * h, h), 0.0);
    EXPECT_EQ(poly6(1.5 * h * h, h), 0.0);
    EXPECT_GT(poly6(0.99 * h * h, h), 0.0);
    EXPECT_NEAR(poly6(0.0, h), 315.0 / (64.0 * std::numbers::pi * std::pow(h, 3)),
                1e-9 / std::pow(h, 3));
  }
}

TEST(SphKernel, GradientMatchesFiniteDifferenceAndPeaksAtHOverRootFive) {
  const double h = 0.7;
  for (double r : {0.05, 0.2, 0.31, 0.5, 0.69}) {
    const double e = 1e-6;
    const double dw = (poly6((r + e) * (r + e), h) - poly6((r - e) * (r - e), h)) / (2 * e);
    EXPECT_NEAR(poly6_gradient_scale(r * r, h) * r, dw, 1e-6 * std::abs(dw) + 1e-9) << r;
  }
  const double rp = poly6_gradient_peak_radius(h);
  const double peak = poly6_gradient_peak(h);
  for (double r = 0.01; r < h; r += 0.01)
    EXPECT_LE(-poly6_gradient_scale(r * r, h) * r, peak * (1 + 1e-12)) << r;
  EXPECT_NEAR(-poly6_gradient_scale(rp * rp, h) * rp, peak, 1e-12 * peak);
  EXPECT_EQ(poly6_gradient_scale(h * h, h), 0.0);
}

TEST(SphGrid, MortonKeyInterleavesBits) {
  EXPECT_EQ(morton_key(1, 0, 0), 1u);
  EXPECT_EQ(morton_key(0, 1, 0), 2u);
  EXPECT_EQ(morton_key(0, 0, 1), 4u);
  EXPECT_EQ(morton_key(3, 3, 3), 63u);
  EXPECT_EQ(morton_key(2, 0, 0), 8u);
  EXPECT_EQ(morton_key((1u << 21) - 1, 0, 0), 0x1249249249249249ULL);
}

TEST(SphGrid, ThreeOrdersGiveTheBruteForceNeighbourSets) {
  for (uint32_t seed : {1u, 2u, 3u}) {
    const Cloud c = random_cloud(1500, 4.0f, seed);
    const float h = 0.3f + 0.1f * static_cast<float>(seed);
    std::vector<std::vector<uint32_t>> expect, ambiguous;
    brute_force(c, h, expect, ambiguous);
    size_t total = 0;
    for (CellOrder order : kOrders)
      for (bool subcells : {true, false}) {
        Grid g;
        g.subcells = subcells;
        build_grid(g, c.x, c.y, c.z, c.m, h, order);
        std::vector<uint32_t> offsets, ids;
        neighbour_lists(g, c.size(), offsets, ids);
        total = 0;
        for (uint32_t i = 0; i < c.size(); ++i) {
          const std::vector<uint32_t> got(ids.begin() + offsets[i], ids.begin() + offsets[i + 1]);
          ASSERT_EQ(without(got, ambiguous[i]), expect[i])
              << to_string(order) << (subcells ? " sub-cells" : " blocks") << " particle " << i;
          total += got.size();
        }
      }
    EXPECT_GT(total, 10u * c.size()) << "the clouds must have neighbours to compare";
  }
}

TEST(SphGrid, SubsetGridSeesOnlyTheSubset) {
  const Cloud c = random_cloud(800, 3.0f, 9);
  std::vector<uint32_t> subset;
  for (uint32_t i = 0; i < c.size(); i += 3) subset.push_back(i);
  const float h = 0.4f;
  for (CellOrder order : kOrders) {
    Grid g;
    build_grid(g, c.x, c.y, c.z, {}, h, order, subset);
    std::vector<uint32_t> offsets, ids;
    neighbour_lists(g, c.size(), offsets, ids);
    for (uint32_t i = 0; i < c.size(); ++i) {
      if (i % 3 != 0) {
        EXPECT_EQ(offsets[i], offsets[i + 1]) << "not in the subset";
        continue;
      }
      std::vector<uint32_t> expect;
      for (uint32_t j : subset) {
        const float dx = c.x[i] - c.x[j], dy = c.y[i] - c.y[j], dz = c.z[i] - c.z[j];
        if (j != i && dx * dx + dy * dy + dz * dz < h * h) expect.push_back(j);
      }
      EXPECT_EQ(std::vector<uint32_t>(ids.begin() + offsets[i], ids.begin() + offsets[i + 1]),
                expect)
          << to_string(order);
    }
  }
}

TEST(SphGrid, RunsPerOctantLinearRowsAndAlignedMortonBlocks) {
  // A full lattice: every cell occupied.
  Cloud c;
  const float h = 0.5f;
  for (int i = 0; i < 12; ++i)
    for (int j = 0; j < 12; ++j)
      for (int k = 0; k < 12; ++k) {
        c.x.push_back(0.37f * i);
        c.y.push_back(0.41f * j);
        c.z.push_back(0.43f * k);
      }
  Grid lin, mor;
  lin.subcells = mor.subcells = false;  // the 2×2×2 block runs
  build_grid(lin, c.x, c.y, c.z, {}, h, CellOrder::Linear);
  build_grid(mor, c.x, c.y, c.z, {}, h, CellOrder::Morton);
  CellRuns runs;
  int aligned_blocks = 0;
  for (uint32_t cell = 0; cell < lin.cell_key.size(); ++cell) {
    cell_runs(lin, cell, runs);
    for (int o = 0; o < 8; ++o) EXPECT_LE(runs.count[o], 4) << "one run per (y, z) row";
  }
  for (uint32_t cell = 0; cell < mor.cell_key.size(); ++cell) {
    cell_runs(mor, cell, runs);
    const auto cc = mor.coord[mor.cell_begin[cell]];
    const bool interior = cc[0] > 1 && cc[1] > 1 && cc[2] > 1 && cc[0] + 2 < mor.dims[0] &&
                          cc[1] + 2 < mor.dims[1] && cc[2] + 2 < mor.dims[2];
    for (int o = 0; o < 8; ++o) {
      const bool aligned = ((cc[0] - 1 + (o & 1)) % 2 == 0) &&
                           ((cc[1] - 1 + ((o >> 1) & 1)) % 2 == 0) &&
                           ((cc[2] - 1 + ((o >> 2) & 1)) % 2 == 0);
      if (interior && aligned) {
        EXPECT_EQ(runs.count[o], 1) << "an aligned 2×2×2 block is one Morton run";
        ++aligned_blocks;
      }
    }
  }
  EXPECT_GT(aligned_blocks, 10);
}

TEST(SphGrid, DensityPassCountsMatchListsAndOrdersAgree) {
  const Cloud c = random_cloud(2000, 4.0f, 5);
  const float h = 0.45f;
  for (CellOrder order : kOrders) {
    Grid g;
    g.subcells = order == CellOrder::Linear;  // both layouts of the density pass
    build_grid(g, c.x, c.y, c.z, c.m, h, order);
    std::vector<float> rho(c.size());
    std::vector<uint32_t> count(c.size());
    density_pass(g, rho, count);
    std::vector<uint32_t> offsets, ids;
    neighbour_lists(g, c.size(), offsets, ids);
    for (uint32_t i = 0; i < c.size(); ++i) {
      ASSERT_EQ(count[i], offsets[i + 1] - offsets[i]) << to_string(order);
      double expect = 0.0;  // double reference: Σ m W, self included
      for (uint32_t k = offsets[i]; k < offsets[i + 1]; ++k) {
        const uint32_t j = ids[k];
        const double dx = c.x[i] - c.x[j], dy = c.y[i] - c.y[j], dz = c.z[i] - c.z[j];
        expect += c.m[j] * poly6(dx * dx + dy * dy + dz * dz, h);
      }
      expect += c.m[i] * poly6(0.0, h);
      ASSERT_NEAR(rho[i], expect, 1e-5 * expect) << to_string(order) << " " << i;
    }
  }
}

TEST(SphGrid, DensityPassIsBitIdenticalForOneAndTwoThreads) {
  const Cloud c = random_cloud(20000, 8.0f, 11);
  for (CellOrder order : kOrders) {
    std::vector<float> rho[2];
    std::vector<uint32_t> count[2];
    for (int t = 0; t < 2; ++t) {
      tbb::task_arena arena(t + 1);
      arena.execute([&] {
        Grid g;
        build_grid(g, c.x, c.y, c.z, c.m, 0.3f, order);
        rho[t].assign(c.size(), 0.0f);
        count[t].assign(c.size(), 0);
        density_pass(g, rho[t], count[t]);
      });
    }
    EXPECT_EQ(0, std::memcmp(rho[0].data(), rho[1].data(), rho[0].size() * sizeof(float)))
        << to_string(order);
    EXPECT_EQ(count[0], count[1]);
  }
}

// The sorted orders' slots are the stable order of the particles' keys (cell key, then octant with
// sub-cells): keys never fall, and particles of one key keep their input order. Boxes from a few
// cells to ~10^4 per axis give keys of 6 to over 40 bits, so the radix sort runs one to four
// passes, with and without skipped digits.
TEST(SphGrid, SlotsAreTheStableOrderOfTheParticlesKeys) {
  for (const float h : {2.0f, 0.4f, 0.05f, 0.003f})
    for (const CellOrder order : {CellOrder::Morton, CellOrder::Linear})
      for (const bool subcells : {true, false}) {
        const Cloud c = random_cloud(3000, 20.0f, 7);
        Grid g;
        g.subcells = subcells;
        build_grid(g, c.x, c.y, c.z, c.m, h, order);
        ASSERT_EQ(g.count, c.size());
        uint64_t previous = 0;
        for (uint32_t s = 0; s < g.count; ++s) {
          const auto& cc = g.coord[s];
          uint64_t key = order == CellOrder::Morton ? morton_key(cc[0], cc[1], cc[2])
                                                    : linear_key(g, cc[0], cc[1], cc[2]);
          if (subcells) key = key << 3 | g.octant[s];
          const std::string at = std::string(to_string(order)) + " h " + std::to_string(h) +
                                 (subcells ? " sub" : "") + " slot " + std::to_string(s);
          if (s > 0) {
            ASSERT_LE(previous, key) << at;
            if (previous == key) ASSERT_LT(g.id[s - 1], g.id[s]) << at;
          }
          previous = key;
        }
      }
}

TEST(SphGrid, EmptyAndNanInputsDoNotBreakTheGrid) {
  Grid g;
  std::vector<float> none;
  build_grid(g, none, none, none, none, 0.2f, CellOrder::Morton);
  EXPECT_EQ(g.count, 0u);
  std::vector<float> x = {0.0f, std::nanf(""), 0.1f}, y = {0.0f, 0.0f, 0.0f},
                     z = {0.0f, 0.0f, 0.0f};
  for (CellOrder order : kOrders) {
    build_grid(g, x, y, z, {}, 0.2f, order);
    std::vector<uint32_t> offsets, ids;
    neighbour_lists(g, 3, offsets, ids);
    EXPECT_EQ(offsets[1] - offsets[0], 1u) << to_string(order);  // 0 sees 2, never the NaN
    EXPECT_EQ(ids[offsets[0]], 2u);
    EXPECT_EQ(offsets[2] - offsets[1], 0u);
  }
}

}  // namespace
}  // namespace phaco::sph
