#pragma once
// Particles binned in a uniform grid, kept up to date by re-binning only the particles that moved,
// for nearest-particle queries whose cost follows the query's ball, not the mesh (issue 17).
//
// The capsule's sleeping particles do not move (seed 003's active node set: only the active set
// is integrated), so after one binning of every particle, a frame re-bins its active set and the
// particles a cut or tear appended; a query probes the cells that meet its ball. Removal from a
// cell is O(1): each particle knows its slot in its cell (swap with the cell's last).
//
// Reads: particles (x, y, z, slots). Writes: PointBins.
#include <cstdint>
#include <span>
#include <unordered_map>
#include <vector>

#include "components/particles.hpp"
#include "engine/core/math.hpp"

namespace phaco::point_bins {

inline constexpr uint32_t kNoParticle = 0xffffffffu;

struct PointBins {
  double cell_mm = 0.25;                                      // edge of a cubic cell
  std::unordered_map<uint64_t, std::vector<uint32_t>> cells;  // cell key -> particles in it
  std::vector<uint64_t> key_of;                               // per particle: its cell, or kNoCell
  std::vector<uint32_t> slot_of;                              // per particle: its index in its cell
};

// Bins every particle of `p` (and forgets what was binned): once, when the body is built.
void bin_all(PointBins& bins, const Particles& p, double cell_mm);

// Re-bins the listed particles (those that moved, or were added since the last call: indices past
// the binned count are added). Dead particles leave their cells. Cost: the list.
void rebin(PointBins& bins, const Particles& p, std::span<const uint32_t> moved);
// Adds every particle appended since the last call ([binned count, p.slots.size())).
void bin_appended(PointBins& bins, const Particles& p);

// The live particle nearest `point` within radius_mm (ties: the lower index), or kNoParticle.
// Probes the cells that meet the ball of radius_mm; positions must be as last binned.
uint32_t nearest(const PointBins& bins, const Particles& p, const Vec3& point, double radius_mm);

}  // namespace phaco::point_bins
