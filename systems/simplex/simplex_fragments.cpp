#include "systems/simplex/simplex_fragments.hpp"

#include <algorithm>
#include <array>
#include <atomic>

#include "engine/schedule/parallel.hpp"

namespace phaco::simplex {
namespace {

// Per-fragment mass and mass-weighted rest centroid, members in ascending order.
void fragment_mass(const SimplexCells& cells, Fragments& f, uint32_t frag) {
  double m = 0, cx = 0, cy = 0, cz = 0;
  for (uint32_t i = f.offsets[frag]; i < f.offsets[frag + 1]; ++i) {
    const uint32_t c = f.members[i];
    const double mc = cells.mass[c];
    m += mc, cx += mc * cells.rest_x[c], cy += mc * cells.rest_y[c], cz += mc * cells.rest_z[c];
  }
  f.mass[frag] = m;
  f.rest_cx[frag] = m > 0 ? cx / m : 0.0;
  f.rest_cy[frag] = m > 0 ? cy / m : 0.0;
  f.rest_cz[frag] = m > 0 ? cz / m : 0.0;
}

// CSR, masses and centroids from dense labels numbered in order of first appearance.
void finish_from_labels(const SimplexCells& cells, Fragments& f, uint32_t count) {
  f.count = count;
  f.offsets.assign(size_t{count} + 1, 0);
  const uint32_t n = cells.size();
  for (uint32_t c = 0; c < n; ++c)
    if (f.label[c] != kNoSimplex) ++f.offsets[f.label[c] + 1];
  for (uint32_t i = 0; i < count; ++i) f.offsets[i + 1] += f.offsets[i];
  f.members.resize(f.offsets[count]);
  std::vector<uint32_t>& cursor = f.members;  // filled in id order: ascending within each fragment
  std::vector<uint32_t> fill(f.offsets.begin(), f.offsets.end() - 1);
  for (uint32_t c = 0; c < n; ++c)
    if (f.label[c] != kNoSimplex) cursor[fill[f.label[c]]++] = c;
  f.mass.resize(count), f.rest_cx.resize(count), f.rest_cy.resize(count), f.rest_cz.resize(count);
  for (uint32_t i = 0; i < count; ++i) fragment_mass(cells, f, i);
}

uint32_t find_root(uint32_t* parent, uint32_t x) {
  for (;;) {
    const uint32_t p = std::atomic_ref<uint32_t>(parent[x]).load(std::memory_order_relaxed);
    if (p == x) return x;
    const uint32_t gp = std::atomic_ref<uint32_t>(parent[p]).load(std::memory_order_relaxed);
    // Path halving: gp is an ancestor of x now and forever (parents only move up), so the store
    // is safe against a concurrent one.
    if (gp != p) std::atomic_ref<uint32_t>(parent[x]).store(gp, std::memory_order_relaxed);
    x = gp;
  }
}

void unite(uint32_t* parent, uint32_t a, uint32_t b) {
  for (;;) {
    a = find_root(parent, a);
    b = find_root(parent, b);
    if (a == b) return;
    if (a > b) std::swap(a, b);
    uint32_t expected = b;  // b must still be a root; the smaller root stays the set's root
    if (std::atomic_ref<uint32_t>(parent[b]).compare_exchange_strong(expected, a,
                                                                     std::memory_order_acq_rel))
      return;
  }
}

// The seed's painting: `label` to every cell reached from `seed` over internal links whose mark
// is still kNoSimplex (the seed's too).
void paint_from(const SimplexCells& cells, uint32_t seed, uint32_t label, uint32_t* mark,
                std::vector<uint32_t>& stack) {
  mark[seed] = label;
  stack.assign(1, seed);
  while (!stack.empty()) {
    const uint32_t c = stack.back();
    stack.pop_back();
    for (uint32_t k = 0; k < 4; ++k) {
      const uint32_t nb = cells.neighbour[c][k];
      if (nb != kNoSimplex && mark[nb] == kNoSimplex) {
        mark[nb] = label;
        stack.push_back(nb);
      }
    }
  }
}

// Mass and rest centroid of `ids` (ascending), summed as fragment_mass sums them.
void piece_mass(const SimplexCells& cells, const uint32_t* ids, uint32_t count, double out[4]) {
  double m = 0, cx = 0, cy = 0, cz = 0;
  for (uint32_t k = 0; k < count; ++k) {
    const uint32_t c = ids[k];
    const double mc = cells.mass[c];
    m += mc, cx += mc * cells.rest_x[c], cy += mc * cells.rest_y[c], cz += mc * cells.rest_z[c];
  }
  out[0] = m;
  out[1] = m > 0 ? cx / m : 0.0, out[2] = m > 0 ? cy / m : 0.0, out[3] = m > 0 ? cz / m : 0.0;
}

// update_fragments after removals of which some may have split their fragment (touched 2): the
// alive members of those fragments are split into connected parts by a flood over internal links
// (a member links to members of its own fragment only), the other touched fragments lose their
// removed members and the untouched keep theirs (and their masses); then every piece is numbered
// by its smallest cell and the table rebuilt. Pieces list members ascending and sum masses over
// them in that order: bit-identical to label_fragments_union_find's table over every cell.
void relabel_split_fragments(const SimplexCells& cells, Fragments& frags, FragmentScratch& s) {
  std::vector<uint32_t>& listed = s.piece_members;  // members of the pieces not kept in place
  s.pieces.clear();
  listed.clear();
  auto add_piece = [&](uint32_t source, uint32_t begin, uint32_t end) {
    FragmentScratch::Piece p{0, source, begin, end, {}};
    if (source != kNoSimplex) {
      p.first = frags.members[begin];
      p.mass = {frags.mass[source], frags.rest_cx[source], frags.rest_cy[source],
                frags.rest_cz[source]};
    } else {
      p.first = listed[begin];
      piece_mass(cells, listed.data() + begin, end - begin, p.mass.data());
    }
    s.pieces.push_back(p);
  };
  s.parent.resize(cells.size());
  std::vector<uint32_t>& alive = s.chunk_roots;  // one fragment's alive members, ascending
  std::vector<uint32_t>& part_start = s.old_to_new;
  for (uint32_t f = 0; f < frags.count; ++f) {
    const uint32_t begin = frags.offsets[f], end = frags.offsets[f + 1];
    if (s.touched[f] == 0) {
      add_piece(f, begin, end);
      continue;
    }
    alive.clear();
    for (uint32_t k = begin; k < end; ++k)
      if (cells.alive[frags.members[k]]) alive.push_back(frags.members[k]);
    if (alive.empty()) continue;  // emptied: dropped
    uint32_t parts = 1;
    if (s.touched[f] == 2) {
      // Flood from each member not yet reached, in ascending order: part p's seed is its
      // smallest cell, so the parts are in the order of their smallest cells.
      for (const uint32_t c : alive) s.parent[c] = kNoSimplex;
      parts = 0;
      for (const uint32_t seed : alive) {
        if (s.parent[seed] != kNoSimplex) continue;
        paint_from(cells, seed, parts++, s.parent.data(), s.stack);
      }
    }
    const auto base = static_cast<uint32_t>(listed.size());
    listed.resize(base + alive.size());
    if (parts == 1) {
      std::copy(alive.begin(), alive.end(), listed.begin() + base);
      add_piece(kNoSimplex, base, static_cast<uint32_t>(listed.size()));
      continue;
    }
    // The parts' members ascending: counted, then placed in id order.
    part_start.assign(size_t{parts} + 1, 0);
    for (const uint32_t c : alive) ++part_start[s.parent[c] + 1];
    for (uint32_t p = 0; p < parts; ++p) part_start[p + 1] += part_start[p];
    for (uint32_t p = 0; p <= parts; ++p) part_start[p] += base;
    for (uint32_t p = 0; p < parts; ++p) add_piece(kNoSimplex, part_start[p], part_start[p]);
    const size_t piece0 = s.pieces.size() - parts;
    for (const uint32_t c : alive) listed[s.pieces[piece0 + s.parent[c]].end++] = c;
    for (uint32_t p = 0; p < parts; ++p) {
      FragmentScratch::Piece& piece = s.pieces[piece0 + p];
      piece.first = listed[piece.begin];
      piece_mass(cells, listed.data() + piece.begin, piece.end - piece.begin, piece.mass.data());
    }
  }
  // Numbered by smallest cell; the table rebuilt in that order.
  std::sort(s.pieces.begin(), s.pieces.end(),
            [](const FragmentScratch::Piece& a, const FragmentScratch::Piece& b) {
              return a.first < b.first;
            });
  const auto count = static_cast<uint32_t>(s.pieces.size());
  std::vector<uint32_t>& table = s.table_members;
  table.clear();
  s.table_offsets.assign(1, 0);
  for (uint32_t i = 0; i < count; ++i) {
    const FragmentScratch::Piece& p = s.pieces[i];
    const uint32_t* ids = (p.source != kNoSimplex ? frags.members.data() : listed.data());
    for (uint32_t k = p.begin; k < p.end; ++k) {
      table.push_back(ids[k]);
      frags.label[ids[k]] = i;
    }
    s.table_offsets.push_back(static_cast<uint32_t>(table.size()));
  }
  frags.members.swap(table);
  frags.offsets.swap(s.table_offsets);
  frags.count = count;
  frags.mass.resize(count), frags.rest_cx.resize(count), frags.rest_cy.resize(count),
      frags.rest_cz.resize(count);
  for (uint32_t i = 0; i < count; ++i) {
    const auto& m = s.pieces[i].mass;
    frags.mass[i] = m[0], frags.rest_cx[i] = m[1], frags.rest_cy[i] = m[2], frags.rest_cz[i] = m[3];
  }
}

}  // namespace

void label_fragments_painting(const SimplexCells& cells, Fragments& out, FragmentScratch& scratch) {
  const uint32_t n = cells.size();
  out.label.assign(n, kNoSimplex);
  uint32_t next = 0;
  for (uint32_t seed = 0; seed < n; ++seed) {
    if (!cells.alive[seed] || out.label[seed] != kNoSimplex) continue;
    paint_from(cells, seed, next++, out.label.data(), scratch.stack);
  }
  finish_from_labels(cells, out, next);
}

void label_fragments_union_find(const SimplexCells& cells, Fragments& out, FragmentScratch& scratch,
                                uint32_t grain) {
  const uint32_t n = cells.size();
  grain = std::max<uint32_t>(grain, 1);
  scratch.parent.resize(n);
  out.label.resize(n);
  uint32_t* parent = scratch.parent.data();
  uint32_t* label = out.label.data();
  parallel_for(0, n, grain, [&](uint32_t b, uint32_t e, int) {
    for (uint32_t c = b; c < e; ++c) parent[c] = c;
  });
  parallel_for(0, n, grain, [&](uint32_t b, uint32_t e, int) {
    for (uint32_t c = b; c < e; ++c) {
      if (!cells.alive[c]) continue;
      for (uint32_t k = 0; k < 4; ++k) {
        const uint32_t nb = cells.neighbour[c][k];
        if (nb != kNoSimplex && nb > c) unite(parent, c, nb);
      }
    }
  });
  // Roots are the smallest ids of their sets; number them in id order over fixed chunks.
  const uint32_t chunks = (n + grain - 1) / grain;
  scratch.chunk_roots.assign(size_t{chunks} + 1, 0);
  uint32_t* chunk_roots = scratch.chunk_roots.data();
  parallel_for(0, chunks, 1, [&](uint32_t b, uint32_t e, int) {
    for (uint32_t ch = b; ch < e; ++ch) {
      uint32_t roots = 0;
      const uint32_t end = std::min(n, (ch + 1) * grain);
      for (uint32_t c = ch * grain; c < end; ++c) {
        const uint32_t r = find_root(parent, c);
        std::atomic_ref<uint32_t>(parent[c]).store(
            r, std::memory_order_relaxed);  // others may still halve paths
        roots += cells.alive[c] && r == c;
      }
      chunk_roots[ch + 1] = roots;
    }
  });
  for (uint32_t ch = 0; ch < chunks; ++ch) chunk_roots[ch + 1] += chunk_roots[ch];
  parallel_for(0, chunks, 1, [&](uint32_t b, uint32_t e, int) {
    for (uint32_t ch = b; ch < e; ++ch) {
      uint32_t next = chunk_roots[ch];
      const uint32_t end = std::min(n, (ch + 1) * grain);
      for (uint32_t c = ch * grain; c < end; ++c)
        label[c] = cells.alive[c] && parent[c] == c ? next++ : kNoSimplex;
    }
  });
  parallel_for(0, n, grain, [&](uint32_t b, uint32_t e, int) {
    for (uint32_t c = b; c < e; ++c)
      if (cells.alive[c] && parent[c] != c) label[c] = label[parent[c]];
  });
  finish_from_labels(cells, out, chunk_roots[chunks]);
}

void confirm_split(const SimplexCells& cells, Removal& r, FragmentScratch& scratch,
                   uint32_t budget) {
  if (!r.may_split) return;
  const uint32_t n = cells.size();
  if (scratch.stamp.size() != n || scratch.stamp_now == 0xffffffffu) {
    scratch.stamp.assign(n, 0);
    scratch.stamp_now = 0;
  }
  const uint32_t now = ++scratch.stamp_now;
  std::array<uint32_t, 4> targets{};
  uint32_t target_count = 0;
  for (uint32_t nb : r.neighbours)
    if (nb != kNoSimplex && cells.alive[nb]) targets[target_count++] = nb;
  if (target_count < 2) {
    r.may_split = false;
    return;
  }
  // Breadth-first from the first neighbour over alive cells (the removed cell has no links left),
  // in a fixed order: the result depends on the structure alone.
  auto& queue = scratch.stack;
  queue.clear();
  queue.push_back(targets[0]);
  scratch.stamp[targets[0]] = now;
  uint32_t found = 1;
  for (size_t head = 0; head < queue.size() && head < budget; ++head) {
    const uint32_t c = queue[head];
    for (uint32_t k = 0; k < 4; ++k) {
      const uint32_t d = cells.neighbour[c][k];
      if (d == kNoSimplex || scratch.stamp[d] == now) continue;
      scratch.stamp[d] = now;
      queue.push_back(d);
      for (uint32_t t = 1; t < target_count; ++t) found += targets[t] == d;
      if (found == target_count) {
        r.may_split = false;
        return;
      }
    }
  }
}

FragmentUpdate update_fragments(const SimplexCells& cells, std::span<const Removal> removals,
                                Fragments& frags, FragmentScratch& scratch) {
  FragmentUpdate result;
  bool may_split = false;
  scratch.touched.assign(frags.count, 0);
  bool unknown = false;  // a removed cell without a fragment: relabel every cell
  for (const Removal& r : removals) {
    if (!r.removed) continue;
    may_split |= r.may_split;
    if (r.cell < frags.label.size() && frags.label[r.cell] != kNoSimplex) {
      uint8_t& t = scratch.touched[frags.label[r.cell]];
      t = std::max<uint8_t>(t, r.may_split ? 2 : 1);
      frags.label[r.cell] = kNoSimplex;
    } else if (r.may_split) {
      unknown = true;
    }
  }
  if (may_split) {
    if (unknown || frags.label.size() != cells.size()) {
      label_fragments_union_find(cells, frags, scratch);  // the same table (the header says why)
    } else {
      relabel_split_fragments(cells, frags, scratch);
    }
    result.relabelled = true;
    result.fragments = frags.count;
    return result;
  }
  // No split: compact the members of touched fragments in place (removed cells out), drop
  // emptied fragments, then restore the numbering by smallest cell id.
  scratch.old_to_new.assign(frags.count, kNoSimplex);
  uint32_t write = 0, count = 0;
  bool renumber = false;
  for (uint32_t f = 0; f < frags.count; ++f) {
    const uint32_t begin = frags.offsets[f], end = frags.offsets[f + 1];
    const uint32_t start = write;
    if (scratch.touched[f]) {
      for (uint32_t i = begin; i < end; ++i)
        if (cells.alive[frags.members[i]]) frags.members[write++] = frags.members[i];
    } else {
      if (write != begin)
        std::copy(frags.members.begin() + begin, frags.members.begin() + end,
                  frags.members.begin() + write);
      write += end - begin;
    }
    if (write == start) {
      renumber = true;  // emptied: dropped
      continue;
    }
    frags.offsets[count] = start;
    frags.mass[count] = frags.mass[f];
    frags.rest_cx[count] = frags.rest_cx[f], frags.rest_cy[count] = frags.rest_cy[f],
    frags.rest_cz[count] = frags.rest_cz[f];
    scratch.touched[count] = scratch.touched[f];
    scratch.old_to_new[f] = count++;
  }
  frags.offsets[count] = write;
  frags.offsets.resize(size_t{count} + 1);
  frags.members.resize(write);
  frags.mass.resize(count), frags.rest_cx.resize(count), frags.rest_cy.resize(count),
      frags.rest_cz.resize(count);
  frags.count = count;
  for (uint32_t f = 0; f < count; ++f)
    if (scratch.touched[f]) fragment_mass(cells, frags, f);
  // A removed smallest cell can move a fragment behind the next one: restore the order (rare).
  bool sorted = true;
  for (uint32_t f = 0; f + 1 < count; ++f)
    sorted &= frags.members[frags.offsets[f]] < frags.members[frags.offsets[f + 1]];
  if (!sorted) {
    std::vector<uint32_t> order(count), rank(count);
    for (uint32_t f = 0; f < count; ++f) order[f] = f;
    std::sort(order.begin(), order.end(), [&](uint32_t a, uint32_t b) {
      return frags.members[frags.offsets[a]] < frags.members[frags.offsets[b]];
    });
    Fragments sorted_frags;
    sorted_frags.count = count;
    sorted_frags.offsets.assign(size_t{count} + 1, 0);
    sorted_frags.members.reserve(frags.members.size());
    for (uint32_t i = 0; i < count; ++i) {
      const uint32_t f = order[i];
      rank[f] = i;
      sorted_frags.members.insert(sorted_frags.members.end(),
                                  frags.members.begin() + frags.offsets[f],
                                  frags.members.begin() + frags.offsets[f + 1]);
      sorted_frags.offsets[i + 1] = static_cast<uint32_t>(sorted_frags.members.size());
      sorted_frags.mass.push_back(frags.mass[f]);
      sorted_frags.rest_cx.push_back(frags.rest_cx[f]);
      sorted_frags.rest_cy.push_back(frags.rest_cy[f]);
      sorted_frags.rest_cz.push_back(frags.rest_cz[f]);
    }
    for (uint32_t& m : scratch.old_to_new)
      if (m != kNoSimplex) m = rank[m];
    sorted_frags.label = std::move(frags.label);
    frags = std::move(sorted_frags);
    renumber = true;
  }
  if (renumber)
    for (uint32_t& l : frags.label)
      if (l != kNoSimplex) l = scratch.old_to_new[l];
  result.fragments = frags.count;
  return result;
}

}  // namespace phaco::simplex
