#include "systems/point_bins/point_bins.hpp"

#include <cmath>
#include <limits>

namespace phaco::point_bins {

namespace {

constexpr uint64_t kNoCell = 0xffffffffffffffffull;

// 21 bits per axis, offset so that ±1 m around the eye's origin packs without sign.
uint64_t pack(int64_t ix, int64_t iy, int64_t iz) {
  constexpr int64_t kOffset = 1 << 20;
  const auto u = [](int64_t v) { return static_cast<uint64_t>(v + kOffset) & 0x1fffffu; };
  return (u(ix) << 42) | (u(iy) << 21) | u(iz);
}

int64_t cell_index(double v, double cell) {
  return static_cast<int64_t>(std::floor(v / cell));
}

uint64_t key_at(const PointBins& b, double x, double y, double z) {
  if (!std::isfinite(x) || !std::isfinite(y) || !std::isfinite(z)) return kNoCell;
  return pack(cell_index(x, b.cell_mm), cell_index(y, b.cell_mm), cell_index(z, b.cell_mm));
}

void leave(PointBins& b, uint32_t i) {
  const uint64_t key = b.key_of[i];
  if (key == kNoCell) return;
  std::vector<uint32_t>& cell = b.cells[key];
  const uint32_t slot = b.slot_of[i];
  const uint32_t last = cell.back();
  cell[slot] = last;
  b.slot_of[last] = slot;
  cell.pop_back();
  if (cell.empty()) b.cells.erase(key);
  b.key_of[i] = kNoCell;
}

void place(PointBins& b, const Particles& p, uint32_t i) {
  if (i >= b.key_of.size()) b.key_of.resize(i + 1, kNoCell), b.slot_of.resize(i + 1, 0);
  const uint64_t key = p.slots.alive(i) ? key_at(b, p.x[i], p.y[i], p.z[i]) : kNoCell;
  if (key == b.key_of[i]) return;
  leave(b, i);
  if (key == kNoCell) return;
  std::vector<uint32_t>& cell = b.cells[key];
  b.key_of[i] = key;
  b.slot_of[i] = static_cast<uint32_t>(cell.size());
  cell.push_back(i);
}

}  // namespace

void bin_all(PointBins& bins, const Particles& p, double cell_mm) {
  bins = PointBins{};
  bins.cell_mm = cell_mm;
  const uint32_t n = p.slots.size();
  bins.key_of.assign(n, kNoCell);
  bins.slot_of.assign(n, 0);
  for (uint32_t i = 0; i < n; ++i) place(bins, p, i);
}

void rebin(PointBins& bins, const Particles& p, std::span<const uint32_t> moved) {
  for (uint32_t i : moved)
    if (i < p.slots.size()) place(bins, p, i);
}

void bin_appended(PointBins& bins, const Particles& p) {
  for (uint32_t i = static_cast<uint32_t>(bins.key_of.size()); i < p.slots.size(); ++i)
    place(bins, p, i);
}

uint32_t nearest(const PointBins& bins, const Particles& p, const Vec3& point, double radius_mm) {
  if (!(radius_mm >= 0.0) || !std::isfinite(point.x()) || !std::isfinite(point.y()) ||
      !std::isfinite(point.z()))
    return kNoParticle;
  const double c = bins.cell_mm;
  const int64_t x0 = cell_index(point.x() - radius_mm, c),
                x1 = cell_index(point.x() + radius_mm, c);
  const int64_t y0 = cell_index(point.y() - radius_mm, c),
                y1 = cell_index(point.y() + radius_mm, c);
  const int64_t z0 = cell_index(point.z() - radius_mm, c),
                z1 = cell_index(point.z() + radius_mm, c);
  uint32_t best_i = kNoParticle;
  double best = radius_mm * radius_mm;
  for (int64_t ix = x0; ix <= x1; ++ix)
    for (int64_t iy = y0; iy <= y1; ++iy)
      for (int64_t iz = z0; iz <= z1; ++iz) {
        const auto it = bins.cells.find(pack(ix, iy, iz));
        if (it == bins.cells.end()) continue;
        for (uint32_t i : it->second) {
          if (!p.slots.alive(i)) continue;
          const double dx = p.x[i] - point.x(), dy = p.y[i] - point.y(), dz = p.z[i] - point.z();
          const double d2 = dx * dx + dy * dy + dz * dz;
          if (d2 < best || (d2 == best && i < best_i)) best = d2, best_i = i;
        }
      }
  return best_i;
}

}  // namespace phaco::point_bins
