#include "systems/sph/grid.hpp"

#include <algorithm>
#include <bit>
#include <cassert>
#include <cmath>

#include "engine/core/invariants.hpp"
#include "engine/schedule/parallel.hpp"

namespace phaco::sph {

const char* to_string(CellOrder order) {
  switch (order) {
    case CellOrder::Morton:
      return "morton";
    case CellOrder::Linear:
      return "linear";
    case CellOrder::UnsortedHash:
      return "unsorted_hash";
  }
  return "?";
}

CellOrder default_order() {
  return CellOrder::Linear;
}

namespace {

// Spreads the low 21 bits of v so that bit k lands on bit 3k.
uint64_t spread3(uint64_t v) {
  v &= 0x1fffff;
  v = (v | v << 32) & 0x1f00000000ffffULL;
  v = (v | v << 16) & 0x1f0000ff0000ffULL;
  v = (v | v << 8) & 0x100f00f00f00f00fULL;
  v = (v | v << 4) & 0x10c30c30c30c30c3ULL;
  v = (v | v << 2) & 0x1249249249249249ULL;
  return v;
}

uint64_t key_of(const Grid& g, uint32_t ix, uint32_t iy, uint32_t iz) {
  return g.order == CellOrder::Morton ? morton_key(ix, iy, iz) : linear_key(g, ix, iy, iz);
}

// Teschner et al. 2003's spatial hash primes, then mixed (the xor of the products alone clusters
// nearby cells into runs of the table, which linear probing turns into long probe sequences).
uint64_t hash_of(uint32_t ix, uint32_t iy, uint32_t iz) {
  uint64_t h = (uint64_t{ix} * 73856093u) ^ (uint64_t{iy} * 19349663u) ^ (uint64_t{iz} * 83492791u);
  h ^= h >> 29;
  h *= 0xbf58476d1ce4e5b9ULL;
  return h ^ (h >> 32);
}

bool inside(const Grid& g, int64_t ix, int64_t iy, int64_t iz) {
  return ix >= 0 && iy >= 0 && iz >= 0 && ix < g.dims[0] && iy < g.dims[1] && iz < g.dims[2];
}

// Stable LSD radix sort of (key, id) by key. The keys' significant bits are split into the fewest
// digits of at most kGridRadixBits, and every pass's histogram is counted in one read of the keys
// (the lens contact grids' keys, about 15-16 bits, still take two passes: the gain is that one
// read, not a pass; keys of 17-22 bits would take two where 8-bit digits took three). A pass
// whose digit is the same for every key is skipped. Any split of the bits gives the one stable
// order by key, so the grid is the same.
constexpr int kGridRadixBits = 11;

void radix_sort(Grid& g, uint32_t n) {
  uint64_t all_or = 0;
  for (uint32_t i = 0; i < n; ++i) all_or |= g.key[i];
  const int bits = 64 - std::countl_zero(all_or);
  if (bits == 0) return;  // every key 0: already in order
  const int passes = (bits + kGridRadixBits - 1) / kGridRadixBits;
  const int width = (bits + passes - 1) / passes;
  const uint32_t radix = 1u << width;
  const uint64_t mask = radix - 1;
  g.histogram.assign(size_t{radix} * passes, 0);
  uint32_t* const hist = g.histogram.data();
  for (uint32_t i = 0; i < n; ++i) {
    const uint64_t k = g.key[i];
    for (int p = 0; p < passes; ++p) ++hist[p * radix + ((k >> (p * width)) & mask)];
  }
  for (int p = 0; p < passes; ++p) {
    uint32_t* const h = hist + static_cast<size_t>(p) * radix;
    const int shift = p * width;
    if (h[(g.key[0] >> shift) & mask] == n) continue;  // one digit: nothing moves
    uint32_t sum = 0;
    for (uint32_t d = 0; d < radix; ++d) {
      const uint32_t c = h[d];
      h[d] = sum;
      sum += c;
    }
    for (uint32_t i = 0; i < n; ++i) {
      const uint32_t dst = h[(g.key[i] >> shift) & mask]++;
      g.key_tmp[dst] = g.key[i];
      g.id_tmp[dst] = g.id[i];
    }
    g.key.swap(g.key_tmp);
    g.id.swap(g.id_tmp);
  }
}

}  // namespace

uint64_t morton_key(uint32_t ix, uint32_t iy, uint32_t iz) {
  return spread3(ix) | spread3(iy) << 1 | spread3(iz) << 2;
}

uint64_t linear_key(const Grid& g, uint32_t ix, uint32_t iy, uint32_t iz) {
  return uint64_t{ix} + uint64_t{g.dims[0]} * (uint64_t{iy} + uint64_t{g.dims[1]} * iz);
}

namespace {

// The unsorted hash's lookup: open addressing on the cell key, then each table entry's particles
// listed contiguously in input order (counts, prefix sums, fill): cell -> list, the particles
// themselves unmoved.
void fill_hash_table(Grid& g, uint32_t n) {
  const uint64_t capacity = std::bit_ceil(uint64_t{2} * n);
  g.table_mask = capacity - 1;
  g.table_key.assign(capacity, kEmptyKey);
  g.table_begin.assign(capacity + 1, 0);
  for (uint32_t s = 0; s < n; ++s) {
    const std::array<uint32_t, 3>& c = g.coord[s];
    uint64_t t = hash_of(c[0], c[1], c[2]) & g.table_mask;
    while (g.table_key[t] != kEmptyKey && g.table_key[t] != g.key[s]) t = (t + 1) & g.table_mask;
    g.table_key[t] = g.key[s];
    g.id_tmp[s] = static_cast<uint32_t>(t);
    ++g.table_begin[t + 1];
  }
  for (uint64_t t = 0; t < capacity; ++t) g.table_begin[t + 1] += g.table_begin[t];
  g.items.resize(n);
  g.table_fill.assign(g.table_begin.begin(), g.table_begin.end() - 1);
  for (uint32_t s = 0; s < n; ++s) g.items[g.table_fill[g.id_tmp[s]]++] = s;
}

// The sorted orders' lookup: the compact cell table over the sorted keys, the sub-cells' ranges
// and, for a small box, the dense table from cell coordinates to cell.
void fill_cell_table(Grid& g, uint32_t n, bool sub) {
  // Compact cell table over the sorted keys.
  g.slot_cell.resize(n);
  const int shift = sub ? 3 : 0;
  for (uint32_t s = 0; s < n; ++s) {
    if (s == 0 || g.key[s] >> shift != g.key[s - 1] >> shift) {
      g.cell_key.push_back(g.key[s] >> shift);
      g.cell_begin.push_back(s);
    }
    g.slot_cell[s] = static_cast<uint32_t>(g.cell_key.size() - 1);
  }
  g.cell_begin.push_back(n);

  g.sub_begin.clear();
  if (sub) {
    const auto cells = static_cast<uint32_t>(g.cell_key.size());
    g.sub_begin.resize(8 * size_t{cells} + 1);
    for (uint32_t c = 0; c < cells; ++c) {
      uint32_t s = g.cell_begin[c];
      for (uint32_t o = 0; o < 8; ++o) {
        g.sub_begin[8 * c + o] = s;
        while (s < g.cell_begin[c + 1] && g.octant[s] == o) ++s;
      }
    }
    g.sub_begin[8 * size_t{cells}] = n;
  }

  // A dense table from cell coordinates to cell index when the box is small enough (the lens
  // always is): one load instead of a binary search per neighbour cell.
  const uint64_t box = uint64_t{g.dims[0]} * g.dims[1] * g.dims[2];
  g.dense_cell.clear();
  if (box <= uint64_t{8} * n + 4096) {
    g.dense_cell.assign(box, kNoSlot);
    for (uint32_t c = 0; c + 1 < g.cell_begin.size(); ++c) {
      const std::array<uint32_t, 3>& cc = g.coord[g.cell_begin[c]];
      g.dense_cell[linear_key(g, cc[0], cc[1], cc[2])] = c;
    }
  }
}

}  // namespace

void build_grid(Grid& g, std::span<const float> x, std::span<const float> y,
                std::span<const float> z, std::span<const float> mass, float h, CellOrder order,
                std::span<const uint32_t> subset, const std::array<float, 6>* box) {
  assert(same_size(x, y, z) && (mass.empty() || same_size(x, mass)) && all_below(subset, x.size()));
  const uint32_t n =
      subset.empty() ? static_cast<uint32_t>(x.size()) : static_cast<uint32_t>(subset.size());
  g.order = order;
  g.h = h;
  g.h2 = h * h;
  g.cell = 2.0 * static_cast<double>(h) * (1.0 + kCellMargin);
  g.count = n;
  g.id.resize(n);
  // Padded so that an 8-wide block may read past the last slot (the reads are masked). Slots
  // below n are all written below: only the padding is zeroed.
  for (std::vector<float>* v : {&g.x, &g.y, &g.z, &g.m}) {
    v->resize(n + kPad);
    std::fill(v->begin() + n, v->end(), 0.0f);
  }
  g.octant.resize(n);
  g.coord.resize(n);
  g.key.resize(n);
  g.key_tmp.resize(n);
  g.id_tmp.resize(n);
  g.cell_key.clear();
  g.cell_begin.clear();
  if (n == 0) {
    g.cell_begin.push_back(0);
    return;
  }
  auto particle = [&](uint32_t i) { return subset.empty() ? i : subset[i]; };

  // Bounds (min/max are exact, so the order of this loop does not matter). NaN never wins.
  double lo[3] = {1e300, 1e300, 1e300}, hi[3] = {-1e300, -1e300, -1e300};
  for (int a = 0; box && a < 3; ++a) lo[a] = (*box)[a], hi[a] = (*box)[a + 3];
  for (uint32_t i = 0; !box && i < n; ++i) {
    const uint32_t p = particle(i);
    const double v[3] = {x[p], y[p], z[p]};
    for (int a = 0; a < 3; ++a) {
      if (v[a] < lo[a]) lo[a] = v[a];
      if (v[a] > hi[a]) hi[a] = v[a];
    }
  }
  const double inv_cell = 1.0 / g.cell;
  for (int a = 0; a < 3; ++a) {
    if (!(lo[a] <= hi[a])) lo[a] = hi[a] = 0.0;  // every coordinate NaN
    g.origin[a] = lo[a] - g.cell;                // one empty layer below: neighbours stay ≥ 0
    const double span_cells = std::floor((hi[a] - g.origin[a]) * inv_cell);
    g.dims[a] = static_cast<uint32_t>(std::min<double>(span_cells, kMaxCellCoord)) + 2;
  }

  const bool sub = g.subcells && order != CellOrder::UnsortedHash;
  // Cell coordinates, octant and key per particle, in input order.
  g.coord_in.resize(n);
  g.octant_in.resize(n);

  parallel_for(0, n, 4096, [&](uint32_t b, uint32_t e, int) {
    for (uint32_t i = b; i < e; ++i) {
      const uint32_t p = particle(i);
      const double v[3] = {x[p], y[p], z[p]};
      std::array<uint32_t, 3> c{};
      uint8_t oct = 0;
      for (int a = 0; a < 3; ++a) {
        double t = (v[a] - g.origin[a]) * inv_cell;
        if (!(t >= 0.0)) t = 0.0;  // NaN lands in cell 0
        t = std::min<double>(t, kMaxCellCoord);
        c[a] = static_cast<uint32_t>(t);
        if (t - c[a] >= 0.5) oct |= static_cast<uint8_t>(1u << a);
      }
      g.coord_in[i] = c;
      g.octant_in[i] = oct;
      g.key[i] = order == CellOrder::Morton ? morton_key(c[0], c[1], c[2])
                                            : linear_key(g, c[0], c[1], c[2]);
      if (sub) g.key[i] = g.key[i] << 3 | oct;
      g.id[i] = i;
    }
  });
  // Sorted orders: id becomes the input positions in key order (stable); the hash keeps input
  // order.
  if (order != CellOrder::UnsortedHash) radix_sort(g, n);

  parallel_for(0, n, 4096, [&](uint32_t b, uint32_t e, int) {
    for (uint32_t s = b; s < e; ++s) {
      const uint32_t i = g.id[s];
      const uint32_t p = particle(i);
      g.id[s] = p;
      g.coord[s] = g.coord_in[i];
      g.octant[s] = g.octant_in[i];
      g.x[s] = x[p];
      g.y[s] = y[p];
      g.z[s] = z[p];
      g.m[s] = mass.empty() ? 1.0f : mass[p];
    }
  });

  if (order == CellOrder::UnsortedHash) {
    fill_hash_table(g, n);
  } else {
    fill_cell_table(g, n, sub);
  }
}

Run cell_range(const Grid& g, int64_t ix, int64_t iy, int64_t iz) {
  if (!inside(g, ix, iy, iz)) return {0, 0};
  if (!g.dense_cell.empty()) {
    const uint32_t c = g.dense_cell[linear_key(
        g, static_cast<uint32_t>(ix), static_cast<uint32_t>(iy), static_cast<uint32_t>(iz))];
    return c == kNoSlot ? Run{0, 0} : Run{g.cell_begin[c], g.cell_begin[c + 1]};
  }
  const uint64_t k =
      key_of(g, static_cast<uint32_t>(ix), static_cast<uint32_t>(iy), static_cast<uint32_t>(iz));
  const auto it = std::lower_bound(g.cell_key.begin(), g.cell_key.end(), k);
  const size_t c = static_cast<size_t>(it - g.cell_key.begin());
  const uint32_t begin = g.cell_begin[c];
  return {begin, (it != g.cell_key.end() && *it == k) ? g.cell_begin[c + 1] : begin};
}

Run hash_cell(const Grid& g, int64_t ix, int64_t iy, int64_t iz) {
  if (!inside(g, ix, iy, iz)) return {0, 0};
  const auto cx = static_cast<uint32_t>(ix), cy = static_cast<uint32_t>(iy),
             cz = static_cast<uint32_t>(iz);
  const uint64_t k = linear_key(g, cx, cy, cz);
  uint64_t s = hash_of(cx, cy, cz) & g.table_mask;
  while (g.table_key[s] != kEmptyKey) {
    if (g.table_key[s] == k) return {g.table_begin[s], g.table_begin[s + 1]};
    s = (s + 1) & g.table_mask;
  }
  return {0, 0};
}

namespace {

// Sub-cell grids: the 27 cells around `c` (kNoSlot where empty).
void subcell_parents(const Grid& g, const std::array<uint32_t, 3>& c, CellRuns& out) {
  // With the dense table, a cell off the box's faces (the usual case: the box has an empty layer
  // below its particles and one above) has its 27 neighbours inside, at fixed steps of the
  // linear key from the lowest one: the same entries as the lookups below, without the tests.
  if (!g.dense_cell.empty() && c[0] >= 1 && c[1] >= 1 && c[2] >= 1 && c[0] + 1 < g.dims[0] &&
      c[1] + 1 < g.dims[1] && c[2] + 1 < g.dims[2]) {
    const size_t sy = g.dims[0], sz = size_t{g.dims[0]} * g.dims[1];
    const uint32_t* lowest = g.dense_cell.data() + linear_key(g, c[0] - 1, c[1] - 1, c[2] - 1);
    for (int dz = 0; dz < 3; ++dz)
      for (int dy = 0; dy < 3; ++dy)
        for (int dx = 0; dx < 3; ++dx)
          out.parent[(dz * 3 + dy) * 3 + dx] = lowest[dz * sz + dy * sy + dx];
    return;
  }
  for (int dz = 0; dz < 3; ++dz)
    for (int dy = 0; dy < 3; ++dy)
      for (int dx = 0; dx < 3; ++dx) {
        const int64_t px = int64_t{c[0]} + dx - 1, py = int64_t{c[1]} + dy - 1,
                      pz = int64_t{c[2]} + dz - 1;
        uint32_t idx = kNoSlot;
        if (inside(g, px, py, pz)) {
          if (!g.dense_cell.empty()) {
            idx = g.dense_cell[linear_key(g, static_cast<uint32_t>(px), static_cast<uint32_t>(py),
                                          static_cast<uint32_t>(pz))];
          } else {
            const uint64_t k = key_of(g, static_cast<uint32_t>(px), static_cast<uint32_t>(py),
                                      static_cast<uint32_t>(pz));
            const auto it = std::lower_bound(g.cell_key.begin(), g.cell_key.end(), k);
            if (it != g.cell_key.end() && *it == k)
              idx = static_cast<uint32_t>(it - g.cell_key.begin());
          }
        }
        out.parent[(dz * 3 + dy) * 3 + dx] = idx;
      }
}

// Sub-cell runs of octant o: the 27 sub-cells of edge h around the particle's sub-cell,
// enumerated x fastest (kSubcellSteps, grid.hpp); a sub-cell whose slots follow the previous
// run's extends it.
void subcell_octant(const Grid& g, int o, CellRuns& out) {
  int m = 0;
  const uint32_t* sub = g.sub_begin.data();
  for (const SubcellStep step : kSubcellSteps[o]) {
    const uint32_t p = out.parent[step.parent];
    if (p == kNoSlot) continue;
    const size_t at = 8 * size_t{p} + step.octant;
    const Run r{sub[at], sub[at + 1]};
    if (r.begin == r.end) continue;
    if (m > 0 && out.runs[o][m - 1].end == r.begin)
      out.runs[o][m - 1].end = r.end;
    else
      out.runs[o][m++] = r;
  }
  out.count[o] = static_cast<uint8_t>(m);
}

// Block runs of octant o: the 2×2×2 block of cells toward which the octant lies, sorted by
// first slot, touching runs merged.
void block_octant(int o, CellRuns& out) {
  const int bx = o & 1, by = (o >> 1) & 1, bz = (o >> 2) & 1;
  Run tmp[8];
  int n = 0;
  for (int dz = 0; dz < 2; ++dz)
    for (int dy = 0; dy < 2; ++dy)
      for (int dx = 0; dx < 2; ++dx) {
        const Run r = out.block[((bz + dz) * 3 + by + dy) * 3 + bx + dx];
        if (r.begin == r.end) continue;
        int k = n++;
        while (k > 0 && tmp[k - 1].begin > r.begin) {  // insertion sort by begin
          tmp[k] = tmp[k - 1];
          --k;
        }
        tmp[k] = r;
      }
  int m = 0;
  for (int i = 0; i < n; ++i) {
    if (m > 0 && out.runs[o][m - 1].end == tmp[i].begin)
      out.runs[o][m - 1].end = tmp[i].end;  // touching runs: one scan
    else
      out.runs[o][m++] = tmp[i];
  }
  out.count[o] = static_cast<uint8_t>(m);
}

}  // namespace

void cell_neighbourhood(const Grid& g, uint32_t cell, CellRuns& out) {
  const std::array<uint32_t, 3> c = g.coord[g.cell_begin[cell]];
  out.ready = 0;
  out.subcells = !g.sub_begin.empty();
  if (out.subcells) {
    subcell_parents(g, c, out);
    return;
  }
  for (int dz = 0; dz < 3; ++dz)
    for (int dy = 0; dy < 3; ++dy)
      for (int dx = 0; dx < 3; ++dx)
        out.block[(dz * 3 + dy) * 3 + dx] =
            cell_range(g, int64_t{c[0]} + dx - 1, int64_t{c[1]} + dy - 1, int64_t{c[2]} + dz - 1);
}

void octant_runs(const Grid& g, int o, CellRuns& out) {
  if (out.ready & (1u << o)) return;
  if (out.subcells)
    subcell_octant(g, o, out);
  else
    block_octant(o, out);
  out.ready = static_cast<uint8_t>(out.ready | (1u << o));
}

void cell_runs(const Grid& g, uint32_t cell, CellRuns& out) {
  cell_neighbourhood(g, cell, out);
  for (int o = 0; o < 8; ++o) octant_runs(g, o, out);
}

}  // namespace phaco::sph
