#include "systems/sph/contact.hpp"

#include <algorithm>
#include <cassert>
#include <cmath>

#include "engine/core/invariants.hpp"
#include "engine/schedule/parallel.hpp"
#include "systems/sph/kernel.hpp"
#include "systems/sph/neighbours.hpp"
#include "systems/sph/simd8.hpp"

namespace phaco::sph {

namespace {

constexpr uint32_t kContactGrain = 256;
constexpr uint32_t kCellGrain = 1024;  // grid cells per chunk of the fragment-range pass

// ∫ u(1 − u²)² du = −(1 − u²)³/6, normalised by the peak u_p(1 − u_p²)², u_p = 1/√5; below
// u_p the shape is 1.
double shape_integral(double from) {
  const double up = 1.0 / std::sqrt(5.0);
  const double peak = up * (1.0 - up * up) * (1.0 - up * up);
  const double a = std::max(from, up);
  const double tail = std::pow(1.0 - a * a, 3) / 6.0 / peak;  // ∫_a^1
  return tail + std::max(0.0, up - from);                     // + ∫_from^up of 1
}

// The pair force's scalar (contact.hpp): f_ij = max(0, k·h − c·v_n) · ĝ(r) · n̂ as s · (x_i − x_j).
// What depends on the parameters alone (h², (h/√5)², the peak's denominator, k·h) is computed once
// per call of fragment_contact instead of once per pair, by the same float operations in the same
// order, so s has the same bits as computed per pair.
struct ContactLaw {
  explicit ContactLaw(const ContactParams& p)
      : h2(p.h * p.h),
        rp2(h2 * 0.2f),  // (h/√5)²
        peak(std::sqrt(rp2) * (h2 - rp2) * (h2 - rp2)),
        push(p.stiffness * p.h),
        damping(p.damping) {}
  float operator()(float r2, float vdotd) const {
    if (!(r2 > 0.0f)) return 0.0f;  // coincident (or NaN): no direction
    if (r2 >= h2) return 0.0f;
    const float r = std::sqrt(r2);
    const float rc2 = std::max(r2, rp2);
    const float rc = std::sqrt(rc2);
    const float dc = h2 - rc2;
    const float shape = (rc * dc * dc) / peak;  // ĝ(r) ∈ [0, 1]
    const float vn = vdotd / r;                 // < 0 when approaching
    const float magnitude = std::max(0.0f, push - damping * vn) * shape;
    return magnitude / r;
  }
  float h2, rp2, peak, push, damping;
};

// Per grid cell (sorted orders): its smallest and largest fragment (cell_lo/cell_hi); with
// sub-cells, also each sub-cell's (from index `cells` on, 8 per cell; empty: lo > hi), which
// other_fragment_runs reads. Whether a cell's 3×3×3 block holds more than one fragment
// (cell_mixed) is decided in the contact pass from the neighbourhood it finds anyway for the
// cell's particles (it was found twice for every mixed cell: here and there).
void fragment_ranges(const Grid& g, std::span<const uint32_t> fragment, ContactScratch& s) {
  const auto cells = static_cast<uint32_t>(g.cell_key.size());
  const bool sub = !g.sub_begin.empty();
  const size_t ranges = sub ? size_t{9} * cells : cells;
  s.cell_lo.resize(ranges), s.cell_hi.resize(ranges);
  parallel_for(0, cells, kCellGrain, [&](uint32_t b, uint32_t e, int) {
    for (uint32_t c = b; c < e; ++c) {
      uint32_t lo = 0xffffffffu, hi = 0;
      if (sub) {
        for (uint32_t o = 0; o < 8; ++o) {
          uint32_t slo = 0xffffffffu, shi = 0;
          for (uint32_t k = g.sub_begin[8 * c + o]; k < g.sub_begin[8 * c + o + 1]; ++k)
            slo = std::min(slo, fragment[g.id[k]]), shi = std::max(shi, fragment[g.id[k]]);
          s.cell_lo[cells + 8 * c + o] = slo, s.cell_hi[cells + 8 * c + o] = shi;
          lo = std::min(lo, slo), hi = std::max(hi, shi);
        }
      } else {
        for (uint32_t k = g.cell_begin[c]; k < g.cell_begin[c + 1]; ++k)
          lo = std::min(lo, fragment[g.id[k]]), hi = std::max(hi, fragment[g.id[k]]);
      }
      s.cell_lo[c] = lo, s.cell_hi[c] = hi;
    }
  });
}

// Whether the 3×3×3 block of cells around `cell` (edge 2h, so every pair within h of its
// particles) holds more than one fragment. Only such a cell can have a contact pair.
bool cell_mixed(const Grid& g, const ContactScratch& s, uint32_t cell, const CellRuns& near) {
  const uint32_t f = s.cell_lo[cell];
  if (s.cell_hi[cell] != f) return true;
  for (int k = 0; k < 27; ++k) {
    uint32_t other = kNoSlot;
    if (near.subcells) {
      other = near.parent[k];
    } else if (near.block[k].begin != near.block[k].end) {
      other = g.slot_cell[near.block[k].begin];
    }
    if (other != kNoSlot && (s.cell_lo[other] != f || s.cell_hi[other] != f)) return true;
  }
  return false;
}

// Sub-cell grids, a particle of octant o of `cell` whose own sub-cell holds fragment f only (so
// every particle of that sub-cell is of f): the runs of its 27 sub-cells without those holding f
// only (the pair test rejects each of their slots: same fragment), merged where one follows the
// previous as subcell_octant's. What is left holds every candidate the test could accept, in the
// same order, so the sums have the same bits; none left: the particle has no pair (its sums stay
// +0, as for a cell that is not mixed, one level finer). One walk decides both, from the
// sub-cells' fragment ranges, once per octant instead of per particle over the candidates.
uint8_t other_fragment_runs(const Grid& g, const ContactScratch& s, uint32_t cells, uint32_t f,
                            int o, const CellRuns& near, Run* out) {
  const uint32_t* sub = g.sub_begin.data();
  const uint32_t* lo = s.cell_lo.data() + cells;
  const uint32_t* hi = s.cell_hi.data() + cells;
  int m = 0;
  for (const SubcellStep step : kSubcellSteps[o]) {
    const uint32_t p = near.parent[step.parent];
    if (p == kNoSlot) continue;
    const size_t at = 8 * size_t{p} + step.octant;
    const Run r{sub[at], sub[at + 1]};
    if (r.begin == r.end || (lo[at] == f && hi[at] == f)) continue;
    if (m > 0 && out[m - 1].end == r.begin)
      out[m - 1].end = r.end;
    else
      out[m++] = r;
  }
  return static_cast<uint8_t>(m);
}

// The contact sums of slots [from, to) (one grid cell's; sorted orders). Eight candidates at a
// time are tested for r² < h² and another fragment (labels in slot order: no gather), which
// rejects the many neighbours of a particle's own fragment without a branch each; the few pairs
// left are summed one by one in candidate order, exactly as a scalar walk over the same runs
// would, so the forces have the same bits.
#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__) && \
    !defined(__SANITIZE_ADDRESS__)
__attribute__((target_clones("avx2", "default")))
#endif
uint64_t
contact_slots(const Grid& g, const ContactParticles& in, const ContactScratch& scratch,
              const ContactLaw& law, Candidates& candidates, uint32_t from, uint32_t to, float* fx,
              float* fy, float* fz) {
  using simd8::F8;
  using simd8::I8;
  using simd8::load8;
  const F8 h2 = simd8::splat(g.h2);
  const float* X = g.x.data();
  const float* Y = g.y.data();
  const float* Z = g.z.data();
  const uint32_t* fragment_slot = scratch.fragment_slot.data();
  const bool sub = !g.sub_begin.empty();
  const auto cells = static_cast<uint32_t>(g.cell_key.size());
  // Per octant of the cell (sub-cell grids): its runs, decided at its first particle; those of an
  // octant whose own sub-cell holds one fragment only without that fragment's sub-cells
  // (other_fragment_runs), the others all 27 (Candidates::runs).
  std::array<std::array<Run, kMaxRuns>, 8> own_runs;
  std::array<std::span<const Run>, 8> octant_runs{};
  uint8_t decided = 0;
  uint64_t pairs = 0;
  for (uint32_t i = from; i < to; ++i) {
    std::span<const Run> runs;
    if (sub) {
      const int o = g.octant[i];
      const auto bit = static_cast<uint8_t>(1u << o);
      if (!(decided & bit)) {
        decided |= bit;
        const size_t own = cells + 8 * size_t{g.slot_cell[i]} + o;
        if (scratch.cell_lo[own] == scratch.cell_hi[own]) {
          octant_runs[o] = {own_runs[o].data(),
                            other_fragment_runs(g, scratch, cells, scratch.cell_lo[own], o,
                                                candidates.neighbourhood(i), own_runs[o].data())};
        } else {
          octant_runs[o] = candidates.runs(i);
        }
      }
      runs = octant_runs[o];
      if (runs.empty()) continue;
    } else {
      runs = candidates.runs(i);
    }
    const uint32_t pi = g.id[i];
    const float xs = g.x[i], ys = g.y[i], zs = g.z[i];
    const F8 xi = simd8::splat(xs), yi = simd8::splat(ys), zi = simd8::splat(zs);
    const I8 fi = simd8::splat(static_cast<int32_t>(fragment_slot[i]));
    float sx = 0.0f, sy = 0.0f, sz = 0.0f;
    for (const Run run : runs) {
      for (uint32_t j = run.begin; j < run.end; j += 8) {
        const F8 dx = xi - load8(X + j), dy = yi - load8(Y + j), dz = zi - load8(Z + j);
        const F8 r2 = dx * dx + dy * dy + dz * dz;
        const I8 hit = (r2 < h2) & (load8(fragment_slot + j) != fi) & simd8::below(j, run.end);
        if (!simd8::any(hit)) continue;
        for (int l = 0; l < 8; ++l) {
          if (!hit[l]) continue;
          const uint32_t pj = g.id[j + l];
          const float vd = (in.vx[pi] - in.vx[pj]) * dx[l] + (in.vy[pi] - in.vy[pj]) * dy[l] +
                           (in.vz[pi] - in.vz[pj]) * dz[l];
          const float s = law(r2[l], vd);
          sx += s * dx[l];
          sy += s * dy[l];
          sz += s * dz[l];
          ++pairs;
        }
      }
    }
    fx[pi] += sx;
    fy[pi] += sy;
    fz[pi] += sz;
  }
  return pairs;
}

}  // namespace

float pair_force_scale(const ContactParams& p, float r2, float vdotd) {
  return ContactLaw(p)(r2, vdotd);
}

ContactStats fragment_contact(const ContactParticles& in, uint32_t fragment_count,
                              const ContactParams& params, ContactScratch& scratch,
                              std::span<float> fx, std::span<float> fy, std::span<float> fz) {
  ContactStats stats;
  if (fragment_count < 2) return stats;
  // Every column per particle, the forces too (a short one would be read or written past its end).
  assert(same_size(in.x, in.y, in.z, in.vx, in.vy, in.vz, in.fragment, in.boundary, fx, fy, fz));
  const auto n = static_cast<uint32_t>(in.x.size());
  if (!in.members.empty()) {
    assert(std::is_sorted(in.members.begin(), in.members.end()) && all_below(in.members, n));
    scratch.members.assign(in.members.begin(), in.members.end());
  } else {
    scratch.members.clear();
    for (uint32_t i = 0; i < n; ++i)
      if (in.boundary[i]) scratch.members.push_back(i);
  }
  stats.particles = static_cast<uint32_t>(scratch.members.size());
  if (stats.particles < 2) return stats;
  Grid& g = scratch.grid;
  build_grid(g, in.x, in.y, in.z, {}, params.h, params.order, scratch.members,
             in.members.empty() ? nullptr : in.members_box);

  const bool sorted = params.order != CellOrder::UnsortedHash;
  const ContactLaw law(params);
  uint64_t twice = 0;
  if (sorted) {
    fragment_ranges(g, in.fragment, scratch);
    // Fragment labels in slot order, padded like the positions (the last block reads past the
    // end; those lanes are masked).
    scratch.fragment_slot.resize(size_t{g.count} + kPad);
    for (uint32_t s = 0; s < g.count; ++s) scratch.fragment_slot[s] = in.fragment[g.id[s]];
    std::fill(scratch.fragment_slot.begin() + g.count, scratch.fragment_slot.end(), 0u);
    twice = parallel_reduce_ordered(
        0u, g.count, kContactGrain, uint64_t{0},
        [&](uint32_t b, uint32_t e) {
          uint64_t pairs = 0;
          Candidates candidates(g);
          // Slots of one cell at a time; a cell whose neighbourhood holds one fragment only has
          // no pair to sum (its slots would add +0 to their forces): skipped.
          for (uint32_t s = b; s < e;) {
            const uint32_t cell = g.slot_cell[s];
            const uint32_t to = std::min(e, g.cell_begin[cell + 1]);
            if (cell_mixed(g, scratch, cell, candidates.neighbourhood(s)))
              pairs += contact_slots(g, in, scratch, law, candidates, s, to, fx.data(), fy.data(),
                                     fz.data());
            s = to;
          }
          return pairs;
        },
        [](uint64_t a, uint64_t b) { return a + b; });
  } else {
    twice = parallel_reduce_ordered(
        0u, g.count, kContactGrain, uint64_t{0},
        [&](uint32_t b, uint32_t e) {
          uint64_t pairs = 0;
          float sx = 0.0f, sy = 0.0f, sz = 0.0f;
          for_each_neighbour(
              g, b, e,
              [&](uint32_t i, uint32_t j, float dx, float dy, float dz, float r2) {
                const uint32_t pi = g.id[i], pj = g.id[j];
                if (in.fragment[pj] == in.fragment[pi]) return;
                const float vd = (in.vx[pi] - in.vx[pj]) * dx + (in.vy[pi] - in.vy[pj]) * dy +
                                 (in.vz[pi] - in.vz[pj]) * dz;
                const float s = law(r2, vd);
                sx += s * dx;
                sy += s * dy;
                sz += s * dz;
                ++pairs;
              },
              [&](uint32_t i) {
                const uint32_t pi = g.id[i];
                fx[pi] += sx;
                fy[pi] += sy;
                fz[pi] += sz;
                sx = sy = sz = 0.0f;
              });
          return pairs;
        },
        [](uint64_t a, uint64_t b) { return a + b; });
  }
  stats.pairs = twice / 2;
  return stats;
}

float stiffness_to_stop(float relative_speed, float reduced_mass, float h, float stop_fraction) {
  const double v = relative_speed;
  const double energy = 0.5 * static_cast<double>(reduced_mass) * v * v;
  const double hh = static_cast<double>(h) * h;
  return static_cast<float>(energy / (hh * shape_integral(stop_fraction)));
}

}  // namespace phaco::sph
