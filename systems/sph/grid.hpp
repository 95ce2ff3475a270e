#pragma once
// Neighbour grid for SPH fragment contact (seed 002 §6.1: "spatial ordering based upon Morton
// curves ... Grid cells are chosen to be of size 2h").
//
// Why 8 cells and not 27. With cells of edge 2h, the ball of radius h around a particle that sits
// in the upper half of its cell along x reaches only the next cell up, and in the lower half only
// the next cell down. So a particle's neighbours lie in the 2×2×2 block made of its own cell and
// the 7 cells toward which it lies (its "octant"): 64 h³ scanned per particle, against 216 h³ for
// the 27-cell block of the same cells (27 cells of edge h would scan 27 h³: the sub-cell option
// below gets that without leaving the seed's 2h cells). The cell edge is 2h·(1 + kCellMargin) so
// that float rounding of a pair at distance just under h can never put it outside the block.
//
//   cell edge 2h:   +-------+-------+
//                   |       |   .   |    particle * in the right half of its cell:
//                   |       |  (*)  |    neighbours in its cell and the one to the right
//                   +-------+-------+    (and likewise along y and z)
//
// Three orders of the particles (CellOrder):
//   Morton        cell key = z-order interleave of the cell coordinates (20 bits each), particles
//                 sorted by key. The 8 cells of a block aligned on even coordinates are one run of
//                 the sorted array; an unaligned block splits into up to 8 runs.
//   Linear        cell key = ix + nx·(iy + ny·iz), particles sorted by key. The two cells of a
//   block
//                 along x have consecutive keys, so each (y, z) row of the block is ONE run: 4
//                 runs.
//   UnsortedHash  particles left in their input order; a hash table maps cell -> list of particle
//                 slots (the classic spatial hash; the baseline the sorted orders are measured
//                 against: every candidate is a random access into the position columns).
// Sorting is a stable LSD radix sort on 64-bit keys (ties keep input order): deterministic.
// Sorted orders keep a compact cell table (sorted unique keys and their first slot), plus a dense
// coordinate -> cell table when the box is small (the lens always is; otherwise binary search).
// The ranges of a cell's neighbours are found once per cell, merged into runs once per octant
// (runs that touch become one, whatever the order, so Linear's rows and Morton's aligned blocks
// come out of the same code) and shared by all the cell's particles.
//
// Sub-cells (Grid::subcells, the default): each cell's particles are also sorted by octant, and a
// particle scans the 27 sub-cells of edge h around its own (27 h³ instead of 64 h³).
//
// Reads: particle positions (x, y, z; mm), optional masses (kg), optional subset of particle
// indices. Writes: Grid (reused across frames: after warm-up nothing allocates).
#include <array>
#include <cstdint>
#include <span>
#include <vector>

namespace phaco::sph {

enum class CellOrder : uint8_t { Morton, Linear, UnsortedHash };

const char* to_string(CellOrder order);

// The order the simulation uses, chosen from the measurement in perf/lens/sph_measure
// (docs/fragment_contact.md). 100k particles, ≈ 28 neighbours each, one core, sub-cells, thread
// CPU time on the 2-core reference VM: Linear 10.0 ms, Morton 10.7 ms, UnsortedHash 152 ms. Linear
// and Morton stay within a few per cent of each other in every row (both sort by cell, which is
// what matters); Linear was ahead more often and builds its keys without bit interleaving.
CellOrder default_order();

// Whether grids scan sub-cells by default (Grid::subcells): 10.0 ms against 12.2 ms for the
// 2×2×2 block at 100k particles (Linear, one core), 2.3× fewer candidates.
inline constexpr bool kDefaultSubcells = true;

// Relative enlargement of the cell edge over 2h (covers float rounding of positions and r²).
inline constexpr double kCellMargin = 1.0e-3;
// Cell coordinates are clamped to [0, kMaxCellCoord]: 20 bits per axis, so a Morton or Linear
// key with the 3 sub-cell bits appended still fits 64 bits.
inline constexpr uint32_t kMaxCellCoord = (1u << 20) - 2;
inline constexpr uint32_t kNoSlot = 0xffffffffu;
// Slots of padding after the last particle in x, y, z, m (SIMD blocks read up to 7 past a run).
inline constexpr uint32_t kPad = 8;

struct Run {
  uint32_t begin = 0, end = 0;  // slots [begin, end)
};

struct Grid {
  // Setting, read by build_grid (sorted orders only): also sort each cell's particles by octant,
  // so a particle scans the 27 sub-cells of edge h around its own (27 h³) instead of the whole
  // 2×2×2 block (64 h³). For Morton this is the same curve one level finer: the key of sub-cell
  // (2ix + bx, 2iy + by, 2iz + bz) is morton(ix, iy, iz)·8 + octant, so every 2h cell is still one
  // range of the array.
  bool subcells = kDefaultSubcells;

  CellOrder order = CellOrder::Morton;
  float h = 0.0f;                      // support, mm
  float h2 = 0.0f;                     // h², mm²
  double cell = 0.0;                   // cell edge 2h·(1 + kCellMargin), mm
  double origin[3] = {0.0, 0.0, 0.0};  // corner of cell (0, 0, 0), mm (one cell below the minimum)
  uint32_t dims[3] = {0, 0, 0};        // cells per axis
  uint32_t count = 0;                  // particles in the grid (slots)

  // Per slot. Sorted orders: slots in key order; UnsortedHash: slots in input order.
  std::vector<uint32_t> id;                    // slot -> particle index in the input spans
  std::vector<float> x, y, z;                  // positions, mm (count + kPad)
  std::vector<float> m;                        // masses (1 when none were given; count + kPad)
  std::vector<uint8_t> octant;                 // bit 0/1/2: upper half of the cell along x/y/z
  std::vector<std::array<uint32_t, 3>> coord;  // cell coordinates
  std::vector<uint32_t> slot_cell;             // sorted orders: index into cell_key

  // Sorted orders: compact cell table.
  std::vector<uint64_t> cell_key;    // sorted unique keys
  std::vector<uint32_t> cell_begin;  // first slot of each cell; back() == count
  // Cell index by linear cell coordinate, kNoSlot for an empty cell; only when the box has at
  // most 8·count + 4096 cells (empty otherwise: binary search in cell_key).
  std::vector<uint32_t> dense_cell;
  // With subcells: first slot of octant o of cell c at [8c + o]; [8·cells] == count.
  std::vector<uint32_t> sub_begin;

  // UnsortedHash: open addressing (linear probing) on the Linear key; the slots of table entry t
  // are items[table_begin[t] .. table_begin[t + 1]), in input order.
  std::vector<uint64_t> table_key;    // kEmptyKey where free
  std::vector<uint32_t> table_begin;  // capacity + 1
  std::vector<uint32_t> items;        // slots grouped by table entry
  std::vector<uint32_t> table_fill;   // build scratch
  uint64_t table_mask = 0;

  // Build scratch.
  std::vector<uint64_t> key, key_tmp;
  std::vector<uint32_t> id_tmp, histogram;
  std::vector<std::array<uint32_t, 3>> coord_in;
  std::vector<uint8_t> octant_in;
};

inline constexpr uint64_t kEmptyKey = ~uint64_t{0};

// Builds the grid over the particles listed in `subset` (all of them when empty). `mass` may be
// empty (unit masses). h > 0.
// `box`, when given, is the particles' min x, y, z and max x, y, z as build_grid's own pass would
// find them (NaN coordinates left out), from a pass of the caller's over them anyway.
void build_grid(Grid& grid, std::span<const float> x, std::span<const float> y,
                std::span<const float> z, std::span<const float> mass, float h, CellOrder order,
                std::span<const uint32_t> subset = {}, const std::array<float, 6>* box = nullptr);

// Cell keys.
uint64_t morton_key(uint32_t ix, uint32_t iy, uint32_t iz);
uint64_t linear_key(const Grid& grid, uint32_t ix, uint32_t iy, uint32_t iz);

// Sorted orders: slots [begin, end) of the cell at (ix, iy, iz); empty when it has no particles.
Run cell_range(const Grid& grid, int64_t ix, int64_t iy, int64_t iz);

// UnsortedHash: the range of `items` listing the cell's slots (empty when it has none).
Run hash_cell(const Grid& grid, int64_t ix, int64_t iy, int64_t iz);

// The candidate runs of the octants of one cell (sorted orders). With subcells: the runs of the
// 27 sub-cells of edge h around the octant's sub-cell; else of the 2×2×2 block of cells.
// Computed lazily: the cell's 27 neighbours once (cell_neighbourhood), then each octant's runs
// the first time a particle of that octant asks (octant_runs). A cell of a sparse subset (the
// boundary cells of fragments in contact) holds a few particles in a few octants, and building
// all eight octants for them dominated the contact pass.
inline constexpr int kMaxRuns = 27;
struct CellRuns {
  std::array<std::array<Run, kMaxRuns>, 8> runs;  // [octant][run]
  std::array<uint8_t, 8> count{};                 // runs per octant
  std::array<uint32_t, 27> parent{};  // sub-cell grids: the 27 neighbouring cells, kNoSlot empty
  std::array<Run, 27> block{};        // block grids: the 27 neighbouring cells' slot ranges
  uint8_t ready = 0;                  // bit o: runs[o] and count[o] are computed
  bool subcells = false;
};
// Sub-cell grids: the 27 sub-cells of edge h around octant o's sub-cell, x fastest, each as the
// neighbouring cell it lies in (index into CellRuns::parent) and its octant there. The sub-cell
// coordinates relative to the parent block's lowest sub-cell are s = 2 + bit per axis, the
// neighbours s − 1 … s + 1 (in [1, 4]): cell u >> 1, octant bit u & 1.
struct SubcellStep {
  uint8_t parent, octant;
};
inline constexpr std::array<std::array<SubcellStep, 27>, 8> kSubcellSteps = [] {
  std::array<std::array<SubcellStep, 27>, 8> t{};
  for (int o = 0; o < 8; ++o) {
    const int sx = 2 + (o & 1), sy = 2 + ((o >> 1) & 1), sz = 2 + ((o >> 2) & 1);
    int k = 0;
    for (int dz = -1; dz <= 1; ++dz)
      for (int dy = -1; dy <= 1; ++dy)
        for (int dx = -1; dx <= 1; ++dx, ++k) {
          const int ux = sx + dx, uy = sy + dy, uz = sz + dz;
          t[o][k] = {static_cast<uint8_t>(((uz >> 1) * 3 + (uy >> 1)) * 3 + (ux >> 1)),
                     static_cast<uint8_t>((ux & 1) | (uy & 1) << 1 | (uz & 1) << 2)};
        }
  }
  return t;
}();
void cell_neighbourhood(const Grid& grid, uint32_t cell, CellRuns& out);
void octant_runs(const Grid& grid, int octant, CellRuns& out);
// Both of the above for all eight octants.
void cell_runs(const Grid& grid, uint32_t cell, CellRuns& out);

}  // namespace phaco::sph
