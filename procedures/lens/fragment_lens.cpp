#include "procedures/lens/fragment_lens.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "engine/schedule/parallel.hpp"
#include "systems/lens_tools/collect_ids.hpp"
#include "systems/sph/environment.hpp"

namespace phaco::lens {
namespace {

constexpr uint32_t kCellGrain = 4096;         // per-cell passes: chunks of cells, in parallel
constexpr uint32_t kRegionBins = 32;          // contact regions' bins per axis (mark_boundary)
constexpr float kCaptureBoxMarginMm = 1e-3f;  // the box around the port's capture ball

// Fragments per chunk of a pass over fragments: about kCellGrain cells (as shape matching).
uint32_t fragment_grain(const FragmentLens& l) {
  const uint32_t cells =
      std::max(1u, l.fragments.offsets.empty() ? 0u : l.fragments.offsets.back());
  return std::max<uint32_t>(
      1, static_cast<uint32_t>(uint64_t{l.fragments.count} * kCellGrain / cells));
}

CellSpans spans(FragmentLens& l) {
  return {l.cells.x, l.cells.y,    l.cells.z,     l.vx,      l.vy,
          l.vz,      l.cells.mass, l.cells.alive, l.hardness};
}

// Which cells take part in fragment contact: cells with an external face (seed 002 §6.1, boundary
// cells only) that lie where their fragment's box meets another fragment's box, both widened by
// the support h. Pairs of boxes come from a sweep along x. Fragments far apart, and the far sides
// of fragments in contact, add nothing to the contact grid (model no more than the scene needs).
void mark_boundary(FragmentLens& l) {
  const uint32_t n = l.cells.size(), nf = l.fragments.count;
  const float h = l.settings.contact.h;
  auto& box = l.fragment_box;  // per fragment: min x, y, z, max x, y, z of its boundary cells
  box.assign(nf, {1e30f, 1e30f, 1e30f, -1e30f, -1e30f, -1e30f});
  // Per fragment over its members, the alive cells (min and max are exact: any order gives the
  // same box): which have an external face (boundary, for now), and the box of those. Removed
  // cells are no member: the last pass below clears their flags.
  parallel_for(0, nf, fragment_grain(l), [&](uint32_t fb, uint32_t fe, int) {
    for (uint32_t f = fb; f < fe; ++f) {
      auto& bx = box[f];
      for (uint32_t k = l.fragments.offsets[f]; k < l.fragments.offsets[f + 1]; ++k) {
        const uint32_t c = l.fragments.members[k];
        uint8_t ext = 0;
        for (uint32_t j = 0; j < 4; ++j) ext |= l.cells.neighbour[c][j] == kNoSimplex;
        l.boundary[c] = ext;
        if (!ext) continue;
        const float p[3] = {l.cells.x[c], l.cells.y[c], l.cells.z[c]};
        for (int a = 0; a < 3; ++a)
          bx[a] = std::min(bx[a], p[a] - h), bx[a + 3] = std::max(bx[a + 3], p[a] + h);
      }
    }
  });
  // Overlaps of the widened boxes: a sweep over the fragments sorted by min x.
  auto& order = l.fragment_order;
  order.resize(nf);
  for (uint32_t f = 0; f < nf; ++f) order[f] = f;
  std::sort(order.begin(), order.end(), [&](uint32_t a, uint32_t b) {
    return box[a][0] < box[b][0] || (box[a][0] == box[b][0] && a < b);
  });
  auto& overlaps = l.overlaps;  // (fragment, box of the region it shares with another)
  overlaps.clear();
  for (uint32_t i = 0; i < nf; ++i) {
    const auto& a = box[order[i]];
    for (uint32_t j = i + 1; j < nf && box[order[j]][0] <= a[3]; ++j) {
      const auto& b = box[order[j]];
      std::array<float, 6> r;
      bool meet = true;
      for (int k = 0; k < 3; ++k) {
        r[k] = std::max(a[k], b[k]), r[k + 3] = std::min(a[k + 3], b[k + 3]);
        meet &= r[k] <= r[k + 3];
      }
      if (!meet) continue;
      overlaps.push_back({order[i], r});
      overlaps.push_back({order[j], r});
    }
  }
  // Which regions a cell may lie in: bins over the regions' extent (edge at least 2h, at most
  // kRegionBins per axis), each listing the regions that meet it; a cell tests its own bin's
  // regions of its fragment only. A region holding a cell meets the cell's bin (the bin index is
  // monotone in the coordinate), so the marks are those of testing every region of the fragment.
  std::array<float, 6> ext{1e30f, 1e30f, 1e30f, -1e30f, -1e30f, -1e30f};
  for (const auto& o : overlaps)
    for (int a = 0; a < 3; ++a)
      ext[a] = std::min(ext[a], o.second[a]), ext[a + 3] = std::max(ext[a + 3], o.second[a + 3]);
  uint32_t dims[3];
  float inv[3];
  for (int a = 0; a < 3; ++a) {
    const float span = std::max(ext[a + 3] - ext[a], 1e-6f);
    dims[a] = std::clamp<uint32_t>(static_cast<uint32_t>(span / (2 * h)) + 1, 1, kRegionBins);
    inv[a] = static_cast<float>(dims[a]) / span;
  }
  auto bin = [&](int a, float v) {
    const float t = (v - ext[a]) * inv[a];
    return t > 0.0f ? std::min(static_cast<uint32_t>(t), dims[a] - 1) : 0u;
  };
  auto& first = l.region_bin_first;
  auto& items = l.region_bin_items;
  const uint32_t bins = dims[0] * dims[1] * dims[2];
  auto each_bin = [&](const std::array<float, 6>& r, auto&& fn) {
    const uint32_t x0 = bin(0, r[0]), x1 = bin(0, r[3]), y0 = bin(1, r[1]), y1 = bin(1, r[4]);
    const uint32_t z0 = bin(2, r[2]), z1 = bin(2, r[5]);
    for (uint32_t z = z0; z <= z1; ++z)
      for (uint32_t y = y0; y <= y1; ++y) {
        const uint32_t row = (z * dims[1] + y) * dims[0];
        for (uint32_t x = x0; x <= x1; ++x) fn(row + x);
      }
  };
  // Counting sort of (bin, region): counts, running ends, then the regions from the last down,
  // each taking the slot below its bin's end, so each bin lists its regions ascending and first[b]
  // ends as the bin's start (no copy of the starts to fill from).
  first.assign(size_t{bins} + 1, 0);
  for (const auto& o : overlaps) each_bin(o.second, [&](uint32_t b) { ++first[b]; });
  for (uint32_t b = 1; b < bins; ++b) first[b] += first[b - 1];
  first[bins] = bins ? first[bins - 1] : 0;
  items.resize(first[bins]);
  for (uint32_t k = static_cast<uint32_t>(overlaps.size()); k-- > 0;)
    each_bin(overlaps[k].second, [&](uint32_t b) { items[--first[b]] = k; });
  // Marks, and for the contact grid the marked cells in id order (collect_ids: the same list as a
  // walk over every cell) and their box (min and max are exact in any order, NaN left out as
  // build_grid does), without those two serial walks in sph::fragment_contact and build_grid.
  constexpr float kInf = std::numeric_limits<float>::infinity();
  const uint32_t chunks =
      (n + lens_tools::detail::kCollectChunk - 1) / lens_tools::detail::kCollectChunk;
  l.boundary_chunk_box.assign(chunks, {kInf, kInf, kInf, -kInf, -kInf, -kInf});
  lens_tools::detail::collect_ids(n, l.scan_ids, l.scan_counts, l.boundary_ids, [&](uint32_t c) {
    if (!l.boundary[c] || !l.cells.alive[c]) {
      l.boundary[c] = 0;
      return false;
    }
    const uint32_t f = l.fragments.label[c];
    const float p[3] = {l.cells.x[c], l.cells.y[c], l.cells.z[c]};
    uint8_t in = 0;
    const uint32_t cell_bin = (bin(2, p[2]) * dims[1] + bin(1, p[1])) * dims[0] + bin(0, p[0]);
    for (uint32_t i = first[cell_bin]; i < first[cell_bin + 1] && !in; ++i) {
      const auto& [g, r] = overlaps[items[i]];
      in = g == f && p[0] >= r[0] && p[0] <= r[3] && p[1] >= r[1] && p[1] <= r[4] && p[2] >= r[2] &&
           p[2] <= r[5];
    }
    l.boundary[c] = in;
    if (!in) return false;
    auto& bx = l.boundary_chunk_box[c / lens_tools::detail::kCollectChunk];
    for (int a = 0; a < 3; ++a) {
      if (p[a] < bx[a]) bx[a] = p[a];
      if (p[a] > bx[a + 3]) bx[a + 3] = p[a];
    }
    return true;
  });
  l.boundary_box = {kInf, kInf, kInf, -kInf, -kInf, -kInf};
  for (const auto& bx : l.boundary_chunk_box)
    for (int a = 0; a < 3; ++a) {
      if (bx[a] < l.boundary_box[a]) l.boundary_box[a] = bx[a];
      if (bx[a + 3] > l.boundary_box[a + 3]) l.boundary_box[a + 3] = bx[a + 3];
    }
}

// A new fragment starts from the rotation of the fragment it came from (no jump): l.fragment_of
// holds the labels before the change.
void carry_rotations(FragmentLens& l) {
  std::vector<Quat> rotations(l.fragments.count, Quat::Identity());
  for (uint32_t f = 0; f < l.fragments.count; ++f) {
    const uint32_t first = l.fragments.members[l.fragments.offsets[f]];
    const uint32_t old = l.fragment_of[first];
    if (old < l.rotations.size()) rotations[f] = l.rotations[old];
  }
  l.rotations.swap(rotations);
  l.max_fragments = std::max(l.max_fragments, l.fragments.count);
}

}  // namespace

void remove_lens_cells(FragmentLens& l, std::span<const uint32_t> cells, FragmentLensStats& st) {
  if (cells.empty()) return;
  l.awake = true;
  l.removals.clear();
  for (uint32_t c : cells) {
    simplex::Removal r = simplex::remove_cell(l.cells, c);
    if (!r.removed) continue;
    // Right after each removal (not after the batch): a split needs one removal whose neighbours
    // it leaves apart, and only the state right after that removal shows it.
    if (r.may_split) simplex::confirm_split(l.cells, r, l.fragment_scratch);
    l.removals.push_back(r);
    l.volume_removed_mm3 += l.cells.volume[c];
  }
  st.removed += static_cast<uint32_t>(l.removals.size());
  l.cells_removed += l.removals.size();
  l.fragment_of = l.fragments.label;
  const simplex::FragmentUpdate u =
      simplex::update_fragments(l.cells, l.removals, l.fragments, l.fragment_scratch);
  st.relabelled = u.relabelled;
  carry_rotations(l);
}

uint32_t crack_lens(FragmentLens& l, std::span<const std::pair<uint32_t, uint32_t>> links) {
  uint32_t broken = 0;
  for (const auto& [cell, face] : links) broken += simplex::break_link(l.cells, cell, face);
  if (broken == 0) return 0;
  l.awake = true;
  l.fragment_of = l.fragments.label;
  simplex::label_fragments_union_find(l.cells, l.fragments, l.fragment_scratch);
  carry_rotations(l);
  l.links_broken += broken;
  ++l.cracks;
  return broken;
}

double alive_mass_kg(const FragmentLens& l) {
  double m = 0;
  for (uint32_t c = 0; c < l.cells.size(); ++c)
    if (l.cells.alive[c]) m += l.cells.mass[c];
  return m;
}

namespace {

// SPH contact as a position correction: each boundary cell is moved by what its contact force
// would move it in one step, F·dt²/m, at most half the support h, and its velocity takes that move.
// A cell is a small part of a rigid fragment, so a force integrated on the cell alone (v += F/m·dt)
// is stable only for stiffness below m/dt² (≈ 5e-4 mN/mm for a level-3 cell at 120 Hz), far too
// soft to keep fragments apart; the bounded move is stable at any stiffness, and the pushed cells
// weigh heavily in the shape match, so the fragment as a whole takes the push.
void apply_contact(FragmentLens& l, FragmentLensStats& st, double dt_s) {
  // The last call's forces and pushes lie on its contact grid's members only (fragment_contact
  // adds to those, the loop below pushes those; make_fragment_lens zeroed all): cleared there
  // instead of over every cell.
  for (const uint32_t c : l.contact_scratch.members)
    l.pushed[c] = 0, l.fx[c] = 0.0f, l.fy[c] = 0.0f, l.fz[c] = 0.0f;
  if (l.fragments.count < 2) return;  // one body: no fragment contact to compute
  mark_boundary(l);
  const sph::ContactParticles p{l.cells.x,      l.cells.y,      l.cells.z,         l.vx,
                                l.vy,           l.vz,           l.fragments.label, l.boundary,
                                l.boundary_ids, &l.boundary_box};
  const sph::ContactStats cs = sph::fragment_contact(p, l.fragments.count, l.settings.contact,
                                                     l.contact_scratch, l.fx, l.fy, l.fz);
  st.contact_particles = cs.particles;
  st.contact_pairs = cs.pairs;
  if (cs.pairs == 0) return;
  const float max_move = 0.5f * l.settings.contact.h, inv_dt = static_cast<float>(1.0 / dt_s);
  const float dt2 = static_cast<float>(dt_s * dt_s);
  // Only the cells in the contact grid can carry a force (ascending, as a walk over all cells).
  for (const uint32_t c : l.contact_scratch.members) {
    if (!l.cells.alive[c] || l.cells.mass[c] <= 0) continue;
    if (l.fx[c] == 0.0f && l.fy[c] == 0.0f && l.fz[c] == 0.0f) continue;
    if (l.fragments.label[c] == l.held_fragment) continue;  // the tip carries it: others give way
    Vec3f d = Vec3f(l.fx[c], l.fy[c], l.fz[c]) * (dt2 / l.cells.mass[c]);  // mN·s²/kg = mm
    if (d.norm() > max_move) d *= max_move / d.norm();
    l.cells.x[c] += d.x(), l.cells.y[c] += d.y(), l.cells.z[c] += d.z();
    l.vx[c] += d.x() * inv_dt, l.vy[c] += d.y() * inv_dt, l.vz[c] += d.z() * inv_dt;
    l.pushed[c] = 1;
  }
}

// The rigid fit can set a cell back out of the bag (by over a millimetre when a crack's halves
// push apart against the wall). With fluidics (the drill that fails on a capsule breach) a cell
// the fit left further out than the lens at rest stands out of the bag (its shoulders, up to
// 0.33 mm with the equator fit, constraints.hpp) is brought back to that distance: fragments
// never leave through the wall, and the resting lens is not squeezed.
constexpr double kRestOverlapMm = 0.35;

// The leash of one alive cell: when it lies more than `leash_mm` out of the bag (the opening
// allowed), it is moved back to `leash_mm` out along the way to its projection
// (lens_tools::constrain on the one cell). It reads and writes that cell's position only, so it
// runs in shape matching's write-back, right after the cell's position is written (one pass over
// the cells instead of two, the same positions as a pass of its own after it).
struct BagLeash {
  const lens_tools::EyeBounds& bounds;
  double leash_mm;
  lens_tools::SurelyInside sure;
  BagLeash(const lens_tools::EyeBounds& b, double leash)
      : bounds(b), leash_mm(leash), sure(b, leash) {}
  // SurelyInside's test with its float operations, without a branch per ball (most cells are
  // well inside; the branches of the short-circuit tests were mispredicted often).
  static bool in_ball(const lens_tools::SurelyInside::FloatBall& b, float x, float y, float z) {
    const float dx = x - b.cx, dy = y - b.cy, dz = z - b.cz;
    return !b.present | (dx * dx + dy * dy + dz * dz <= b.r2);
  }
  static bool surely_inside(const lens_tools::SurelyInside& s, float x, float y, float z) {
    const bool open = (s.open2 >= 0) & (x * x + y * y < s.open2);
    return (open | in_ball(s.anterior, x, y, z)) & in_ball(s.posterior, x, y, z) &
           in_ball(s.cornea, x, y, z);
  }
  [[gnu::noinline]] void pull_back(FragmentLens& l, uint32_t c) const {
    const Vec3 p(l.cells.x[c], l.cells.y[c], l.cells.z[c]);
    if (lens_tools::inside_bounds(p, bounds, leash_mm)) return;
    float x = l.cells.x[c], y = l.cells.y[c], z = l.cells.z[c], vx = 0, vy = 0, vz = 0;
    const float mass = l.cells.mass[c], hardness = 0;
    const uint8_t alive = 1;
    const CellSpans one{{&x, 1},  {&y, 1},    {&z, 1},     {&vx, 1},      {&vy, 1},
                        {&vz, 1}, {&mass, 1}, {&alive, 1}, {&hardness, 1}};
    lens_tools::constrain(one, bounds, {});
    const Vec3 q(x, y, z), out = p - q;
    const double len = out.norm();
    if (!(len > leash_mm)) return;
    const Vec3 r = q + out * (leash_mm / len);
    l.cells.x[c] = static_cast<float>(r.x()), l.cells.y[c] = static_cast<float>(r.y()),
    l.cells.z[c] = static_cast<float>(r.z());
  }
};

void match_shapes(FragmentLens& l, FragmentLensStats& st, double dt_s,
                  const std::optional<BagLeash>& leash) {
  const uint32_t n = l.cells.size();
  parallel_for(0, n, kCellGrain, [&](uint32_t b, uint32_t e, int) {
    for (uint32_t c = b; c < e; ++c) {
      l.current[c] = Vec3f(l.cells.x[c], l.cells.y[c], l.cells.z[c]);
      // The held fragment goes where the tip takes it, through the other fragments (it is not
      // pushed), but not through the bag: its cells the bag moved stay heavy.
      const bool held = l.fragments.label[c] == l.held_fragment;
      l.match_mass[c] = sph::heavy_weight(l.cells.mass[c], l.contact[c] | (!held && l.pushed[c]));
    }
  });
  const shape_match::FragmentList list{l.fragments.offsets, l.fragments.members};
  st.match = shape_match::match_lens<float>(l.rest, l.current, l.match_mass, list, l.rotations,
                                            l.settings.match);
  const float inv_dt = static_cast<float>(1.0 / dt_s);
  parallel_for(0, n, kCellGrain, [&](uint32_t b, uint32_t e, int) {
    // The leash's float test on a copy of its balls made here, in registers: read through the
    // leash, the compiler loaded all of them again for every cell, since the loop's float stores
    // might have been to them. The same test, the same positions.
    const bool leashed = leash.has_value();
    const lens_tools::SurelyInside sure =
        leashed ? leash->sure : lens_tools::SurelyInside(l.settings.bounds, 0);
    for (uint32_t c = b; c < e; ++c) {
      if (!l.cells.alive[c]) continue;
      const Vec3f to = l.current[c];
      const Vec3f d = to - Vec3f(l.cells.x[c], l.cells.y[c], l.cells.z[c]);
      l.cells.x[c] = to.x(), l.cells.y[c] = to.y(), l.cells.z[c] = to.z();
      l.vx[c] += d.x() * inv_dt, l.vy[c] += d.y() * inv_dt, l.vz[c] += d.z() * inv_dt;
      if (leashed && !BagLeash::surely_inside(sure, to.x(), to.y(), to.z())) leash->pull_back(l, c);
    }
  });
}

// Ultrasound on a held fragment: the vacuum draws it into the port as fast as the tip emulsifies
// it (lens_tools/fluidics.hpp, emulsify_rate_mm3_s at full power): its cells nearest the port,
// within two port radii of it, go first, each costing its volume / (1 − hardness) of the step's
// budget (a hard nucleus takes longer, and more energy). Appended to this step's removals.
void feed_held(FragmentLens& l, const Vec3& port, double power, double dt_s) {
  const bool held = l.held_cell < l.cells.size() && l.cells.alive[l.held_cell];
  if (!held) {
    l.feed_budget_mm3 = 0;
    return;
  }
  const uint32_t f = l.fragments.label[l.held_cell];
  // What the tip could not take (nothing at the port) is not saved up beyond a few steps.
  const double per_step = l.settings.fluid.emulsify_rate_mm3_s * power * dt_s;
  l.feed_budget_mm3 = std::min(l.feed_budget_mm3 + per_step, 4 * per_step);
  const float reach = static_cast<float>(2 * l.settings.fluid.port_radius_mm);
  const Vec3f p = port.cast<float>();
  const auto taken = [&](uint32_t c) {
    return std::find(l.removed.begin(), l.removed.end(), c) != l.removed.end();
  };
  // The fragment's cells within reach not yet taken, nearest first (ties: lower id, as a walk
  // over the members in id order keeping the first of equals): one pass, then in order.
  auto& near = l.feed_candidates;
  near.clear();
  for (uint32_t k = l.fragments.offsets[f]; k < l.fragments.offsets[f + 1]; ++k) {
    const uint32_t c = l.fragments.members[k];
    const float d = (Vec3f(l.cells.x[c], l.cells.y[c], l.cells.z[c]) - p).squaredNorm();
    if (d <= reach * reach && !taken(c)) near.emplace_back(d, c);
  }
  std::sort(near.begin(), near.end());
  for (size_t i = 0; i < near.size() && i < 64; ++i) {
    const uint32_t best = near[i].second;
    const double cost = l.cells.volume[best] / std::max(1e-3, 1.0 - double(l.hardness[best]));
    if (cost > l.feed_budget_mm3) break;
    l.feed_budget_mm3 -= cost;
    l.removed.push_back(best);
    l.emulsified_mass_kg += l.cells.mass[best];
  }
}

// The chopper and the probe pushing apart across a trench (lens_tools/crack.hpp).
void crack(FragmentLens& l, const LensTools& tools, FragmentLensStats& st) {
  const lens_tools::CrackCells cc{l.cells.x,     l.cells.y,  l.cells.z,
                                  l.cells.alive, l.hardness, l.fragments.label};
  st.push = lens_tools::push_apart(cc, *tools.probe_tip, *tools.chopper_tip, l.settings.crack,
                                   l.crack_state);
  if (!st.push.crack) return;
  lens_tools::links_across(cc, l.cells.neighbour, st.push.fragment, st.push.mid, st.push.normal,
                           l.crack_links);
  st.links_broken = crack_lens(l, l.crack_links);
  if (st.links_broken) l.held_fragment = kNoSimplex;  // labels changed: hold afresh
}

// Occlusion, vacuum and holding at the probe's port (lens_tools/fluidics.hpp). The held fragment
// is known by one of its cells (the farthest from the port, the last the tip takes), since labels
// are renumbered when cells go.
void hold_at_port(FragmentLens& l, const LensTools& tools, FragmentLensStats& st, double dt_s) {
  const lens_tools::FluidicsSettings& fs = l.settings.fluid;
  lens_tools::PortCover cover;
  if (tools.probe_tip && tools.aspirating)
    cover = lens_tools::port_cover(spans(l), l.cells.volume, l.fragments.label, l.fragments.count,
                                   *tools.probe_tip, fs, l.cover_scratch);
  l.vacuum_mmhg =
      lens_tools::step_vacuum(l.vacuum_mmhg, tools.aspirating, cover.occluded, fs, dt_s);
  // A fragment is taken by an occluded port; once held it stays while it is still within the
  // port's reach and the vacuum, decaying at the line's rate once the port opens, outweighs it.
  // The fragment already held keeps the port (a crumb of it in the port does not take over).
  uint32_t f = cover.occluded ? cover.fragment : kNoSimplex;
  const bool was_held = l.held_cell < l.cells.size() && l.cells.alive[l.held_cell];
  if (was_held && tools.probe_tip && tools.aspirating) f = l.fragments.label[l.held_cell];
  l.held_fragment = kNoSimplex;
  l.held_cell = kNoSimplex;
  if (f != kNoSimplex) {
    const double mass = l.fragments.mass[f];
    const bool light = mass <= fs.max_held_mass_fraction * l.initial_mass_kg;
    const Vec3f port = tools.probe_tip->cast<float>();
    float nearest = std::numeric_limits<float>::infinity(), farthest = -1;
    uint32_t far_cell = kNoSimplex, near_cell = kNoSimplex;
    for (uint32_t k = l.fragments.offsets[f]; k < l.fragments.offsets[f + 1]; ++k) {
      const uint32_t c = l.fragments.members[k];
      const float d = (Vec3f(l.cells.x[c], l.cells.y[c], l.cells.z[c]) - port).norm();
      if (d < nearest) nearest = d, near_cell = c;
      if (d > farthest) farthest = d, far_cell = c;
    }
    if (near_cell != kNoSimplex)
      l.held_nearest = Vec3(l.cells.x[near_cell], l.cells.y[near_cell], l.cells.z[near_cell]);
    const bool reach = nearest <= static_cast<float>(fs.hold_reach_mm);
    if (light && reach &&
        lens_tools::holding_force_mn(l.vacuum_mmhg, fs) > mass * fs.gravity_mm_s2) {
      l.held_fragment = f;
      l.held_cell = far_cell;
      l.awake = true;
    }
  }
  st.occluded = cover.occluded;
  st.cover_fraction = cover.fraction;
  st.held = l.held_fragment != kNoSimplex;
  st.vacuum_mmhg = l.vacuum_mmhg;
}

}  // namespace

FragmentLens make_fragment_lens(const TetMesh& mesh, const FragmentLensSettings& settings) {
  FragmentLens l;
  l.settings = settings;
  l.cells = simplex::build_cells(mesh, settings.density_kg_mm3);
  const uint32_t n = l.cells.size();
  l.vx.assign(n, 0.0f), l.vy.assign(n, 0.0f), l.vz.assign(n, 0.0f);
  l.hardness.resize(n);
  for (uint32_t c = 0; c < n; ++c) {
    const double h =
        l.cells.region[c] ? settings.nucleus_hardness : 0.5 * settings.nucleus_hardness;
    l.hardness[c] = static_cast<float>(h);
  }
  l.contact.assign(n, 0);
  l.fx.assign(n, 0.0f), l.fy.assign(n, 0.0f), l.fz.assign(n, 0.0f);
  l.boundary.assign(n, 0);
  l.pushed.assign(n, 0);
  l.rest.resize(n), l.current.resize(n), l.match_mass.resize(n);
  for (uint32_t c = 0; c < n; ++c)
    l.rest[c] = Vec3f(l.cells.rest_x[c], l.cells.rest_y[c], l.cells.rest_z[c]);
  simplex::label_fragments_painting(l.cells, l.fragments, l.fragment_scratch);
  l.rotations.assign(l.fragments.count, Quat::Identity());
  l.removed.reserve(1024);
  l.initial_mass_kg = alive_mass_kg(l);
  return l;
}

FragmentLensStats step_fragment_lens(FragmentLens& l, const LensTools& tools, const CounterRng& rng,
                                     uint64_t frame, double dt_s) {
  FragmentLensStats st;
  ++l.steps;
  const CellSpans cells = spans(l);
  const bool fluidics = l.settings.fluidics;
  // With fluidics the line's vacuum, not a fixed one, pulls at the port.
  std::optional<lens_tools::Aspirator> aspirator = tools.aspirator;
  if (fluidics && aspirator) aspirator->vacuum_mmhg = l.vacuum_mmhg;
  // 2. erosion (before the lens wakes: the first removal is what wakes it)
  l.removed.clear();
  if (tools.phaco)
    lens_tools::erode(cells, *tools.phaco, l.settings.erosion, rng, frame, dt_s, l.erosion,
                      l.removed);
  for (const uint32_t c : l.removed) l.emulsified_mass_kg += l.cells.mass[c];
  if (aspirator) {  // what reached the port is taken in
    const Vec3f port = aspirator->port.cast<float>();
    // With fluidics and ultrasound on, what is emulsified in the port's lumen goes with the flow.
    const bool lumen = fluidics && tools.phaco && tools.phaco->power > 0;
    const double capture = lumen ? l.settings.fluid.port_radius_mm : l.settings.capture_mm;
    const float r2 = static_cast<float>(capture * capture);
    // With fluidics, without ultrasound only a piece that fits through the port passes it.
    const double passes_kg = fluidics && !(tools.phaco && tools.phaco->power > 0)
                                 ? l.settings.density_kg_mm3 * 4.0 / 3.0 * M_PI *
                                       std::pow(l.settings.fluid.port_radius_mm, 3)
                                 : std::numeric_limits<double>::infinity();
    const uint32_t before = static_cast<uint32_t>(l.removed.size());
    // A cell farther than the capture radius from the port along one axis (the radius widened by
    // kCaptureBoxMarginMm, ≫ float rounding of d²) is outside the ball: rejected before the rest.
    const float box = static_cast<float>(capture) + kCaptureBoxMarginMm;
    lens_tools::detail::collect_ids(
        l.cells.size(), l.scan_ids, l.scan_counts, l.scan_hits, [&](uint32_t c) {
          if (!(std::abs(l.cells.x[c] - port.x()) <= box)) return false;
          if (!(std::abs(l.cells.y[c] - port.y()) <= box &&
                std::abs(l.cells.z[c] - port.z()) <= box))
            return false;
          if (!l.cells.alive[c]) return false;
          const Vec3f d = Vec3f(l.cells.x[c], l.cells.y[c], l.cells.z[c]) - port;
          return d.squaredNorm() < r2 && l.fragments.mass[l.fragments.label[c]] <= passes_kg &&
                 !std::binary_search(l.removed.begin(), l.removed.begin() + before, c);
        });
    for (const uint32_t c : l.scan_hits) {  // in id order, as the masses were always summed
      l.removed.push_back(c);
      l.aspirated_mass_kg += l.cells.mass[c];
    }
    st.aspirated = static_cast<uint32_t>(l.removed.size()) - before;
    l.cells_aspirated += st.aspirated;
  }
  if (fluidics && tools.phaco && tools.phaco->power > 0 && tools.probe_tip)
    feed_held(l, *tools.probe_tip, tools.phaco->power, dt_s);
  remove_lens_cells(l, l.removed, st);
  if (fluidics && tools.probe_tip && tools.chopper_tip) crack(l, tools, st);
  if (tools.hook || aspirator) l.awake = true;
  st.fragments = l.fragments.count;
  if (fluidics) hold_at_port(l, tools, st, dt_s);
  if (!l.awake) return st;
  // 3. tools change velocities; 1. gravity and viscosity, then the move; 4. fragment contact
  if (tools.hook) lens_tools::drag_with_hook(cells, *tools.hook, l.settings.hook, dt_s);
  if (aspirator) lens_tools::aspirate(cells, *aspirator, l.settings.aspirator, dt_s);
  lens_tools::integrate(cells, l.settings.medium, dt_s);
  if (fluidics && l.held_fragment < l.fragments.count && tools.probe_tip) {
    const uint32_t f = l.held_fragment;
    const std::span<const uint32_t> members(l.fragments.members.data() + l.fragments.offsets[f],
                                            l.fragments.size_of(f));
    lens_tools::draw_to_tip(cells, members, *tools.probe_tip, tools.probe_velocity, l.held_nearest,
                            l.settings.fluid, dt_s);
  }
  apply_contact(l, st, dt_s);
  // 5. constraints, 6. shape matching
  lens_tools::constrain(cells, l.settings.bounds, l.contact);
  // ... and with fluidics each cell leashed to the bag as its position is written (BagLeash).
  std::optional<BagLeash> leash;
  if (fluidics) leash.emplace(l.settings.bounds, kRestOverlapMm);
  match_shapes(l, st, dt_s, leash);
  return st;
}

}  // namespace phaco::lens
