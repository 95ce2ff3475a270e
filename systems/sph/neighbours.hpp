#pragma once
// Neighbour traversal over a Grid (grid.hpp) and the SPH neighbour pass built on it.
//
// for_each_neighbour visits, for every slot i of a slot range, every slot j ≠ i with
// |x_i − x_j|² < h² (float, r² = dx² + dy² + dz² with dx = x_i − x_j: the same bits for (i, j)
// and (j, i)). Neighbours come in the order of the grid (runs for sorted orders, hash lists for
// UnsortedHash), which depends only on the input, so per-particle sums are deterministic; a pass
// runs parallel_for over slots and each slot writes only its own outputs.
//
// The density pass (MCG03 eq. 3, ρ_i = Σ_j m_j W(r_ij, h), the particle itself included) is the
// "neighbour pass" the perf harness times: every candidate (the 2×2×2 block, or the 27 sub-cells)
// is tested, and the few inside h are summed. Its sorted-order inner loop runs eight candidates at
// a time (vector extensions) into eight lane sums added in a fixed order.
//
// Reads: Grid. Writes: the pass's per-particle outputs (indexed by particle, not slot).
#include <cstdint>
#include <span>
#include <vector>

#include "systems/sph/grid.hpp"

namespace phaco::sph {

// The candidate runs of slots visited in increasing order (sorted orders): the octant's runs of
// the 2×2×2 block (or its 27 sub-cells), the cell's neighbourhood found once per cell and each
// octant's runs once, shared by the cell's particles.
class Candidates {
 public:
  explicit Candidates(const Grid& g) : g_(g) {}

  // The neighbourhood of slot i's cell (CellRuns::parent or block; valid until the next call).
  const CellRuns& neighbourhood(uint32_t i) {
    if (g_.slot_cell[i] != cell_) {
      cell_ = g_.slot_cell[i];
      cell_neighbourhood(g_, cell_, cell_runs_);
    }
    return cell_runs_;
  }

  // The runs of slot i (valid until the next call).
  std::span<const Run> runs(uint32_t i) {
    neighbourhood(i);
    const uint8_t o = g_.octant[i];
    if (!(cell_runs_.ready & (1u << o))) octant_runs(g_, o, cell_runs_);
    return {cell_runs_.runs[o].data(), cell_runs_.count[o]};
  }

 private:
  const Grid& g_;
  uint32_t cell_ = kNoSlot;
  CellRuns cell_runs_;
};

// fn(i, j, dx, dy, dz, r2) for every neighbour j of every slot i in [begin, end); done(i) after
// the last neighbour of i.
template <class Fn, class Done>
void for_each_neighbour(const Grid& g, uint32_t begin, uint32_t end, Fn&& fn, Done&& done) {
  const float h2 = g.h2;
  if (g.order == CellOrder::UnsortedHash) {
    for (uint32_t i = begin; i < end; ++i) {
      const float xi = g.x[i], yi = g.y[i], zi = g.z[i];
      const std::array<uint32_t, 3>& c = g.coord[i];
      const uint8_t o = g.octant[i];
      const int64_t bx = int64_t{c[0]} - 1 + (o & 1), by = int64_t{c[1]} - 1 + ((o >> 1) & 1),
                    bz = int64_t{c[2]} - 1 + ((o >> 2) & 1);
      for (int dz = 0; dz < 2; ++dz)
        for (int dy = 0; dy < 2; ++dy)
          for (int dx = 0; dx < 2; ++dx)
            for (const Run cell = hash_cell(g, bx + dx, by + dy, bz + dz);
                 const uint32_t j :
                 std::span<const uint32_t>(g.items).subspan(cell.begin, cell.end - cell.begin)) {
              const float ddx = xi - g.x[j], ddy = yi - g.y[j], ddz = zi - g.z[j];
              const float r2 = ddx * ddx + ddy * ddy + ddz * ddz;
              if (r2 < h2 && j != i) fn(i, j, ddx, ddy, ddz, r2);
            }
      done(i);
    }
    return;
  }
  Candidates candidates(g);
  for (uint32_t i = begin; i < end; ++i) {
    const float xi = g.x[i], yi = g.y[i], zi = g.z[i];
    for (const Run run : candidates.runs(i)) {
      for (uint32_t j = run.begin; j < run.end; ++j) {
        const float ddx = xi - g.x[j], ddy = yi - g.y[j], ddz = zi - g.z[j];
        const float r2 = ddx * ddx + ddy * ddy + ddz * ddz;
        if (r2 < h2 && j != i) fn(i, j, ddx, ddy, ddz, r2);
      }
    }
    done(i);
  }
}

template <class Fn>
void for_each_neighbour(const Grid& g, uint32_t begin, uint32_t end, Fn&& fn) {
  for_each_neighbour(g, begin, end, fn, [](uint32_t) {});
}

// Per particle (indexed like the input spans; particles outside the grid untouched): density
// ρ = Σ m_j W (self included; kg/mm³ with masses in kg) and the neighbour count (self excluded).
// Parallel over slots; bit-identical for any thread count.
void density_pass(const Grid& grid, std::span<float> density, std::span<uint32_t> neighbours);

// Neighbour lists by particle index, each sorted ascending (tests, tools; allocates).
void neighbour_lists(const Grid& grid, uint32_t particle_count, std::vector<uint32_t>& offsets,
                     std::vector<uint32_t>& ids);

}  // namespace phaco::sph
