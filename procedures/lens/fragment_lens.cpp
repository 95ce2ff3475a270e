#include "procedures/lens/fragment_lens.hpp"

#include <algorithm>
#include <cmath>

#include "engine/schedule/parallel.hpp"
#include "systems/sph/environment.hpp"

namespace phaco::lens {
namespace {

constexpr uint32_t kCellGrain = 4096;  // per-cell passes: chunks of cells, in parallel

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
  for (uint32_t c = 0; c < n; ++c) {
    uint8_t b = 0;
    if (l.cells.alive[c]) {
      for (uint32_t k = 0; k < 4; ++k) b |= l.cells.neighbour[c][k] == kNoSimplex;
    }
    l.boundary[c] = b;
    if (!b) continue;
    auto& bx = box[l.fragments.label[c]];
    const float p[3] = {l.cells.x[c], l.cells.y[c], l.cells.z[c]};
    for (int a = 0; a < 3; ++a)
      bx[a] = std::min(bx[a], p[a] - h), bx[a + 3] = std::max(bx[a + 3], p[a] + h);
  }
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
  std::sort(overlaps.begin(), overlaps.end(),
            [](const auto& a, const auto& b) { return a.first < b.first; });
  auto& first = l.fragment_first_overlap;  // CSR into overlaps, per fragment
  first.assign(nf + 1, 0);
  for (const auto& o : overlaps) ++first[o.first + 1];
  for (uint32_t f = 0; f < nf; ++f) first[f + 1] += first[f];
  for (uint32_t c = 0; c < n; ++c) {
    if (!l.boundary[c]) continue;
    const uint32_t f = l.fragments.label[c];
    const float p[3] = {l.cells.x[c], l.cells.y[c], l.cells.z[c]};
    uint8_t in = 0;
    for (uint32_t k = first[f]; k < first[f + 1] && !in; ++k) {
      const auto& r = overlaps[k].second;
      in = p[0] >= r[0] && p[0] <= r[3] && p[1] >= r[1] && p[1] <= r[4] && p[2] >= r[2] &&
           p[2] <= r[5];
    }
    l.boundary[c] = in;
  }
}

}  // namespace

// A new fragment starts from the rotation of the fragment it came from (no jump).
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
  std::vector<Quat> rotations(l.fragments.count, Quat::Identity());
  for (uint32_t f = 0; f < l.fragments.count; ++f) {
    const uint32_t first = l.fragments.members[l.fragments.offsets[f]];
    const uint32_t old = l.fragment_of[first];
    if (old < l.rotations.size()) rotations[f] = l.rotations[old];
  }
  l.rotations.swap(rotations);
  l.max_fragments = std::max(l.max_fragments, l.fragments.count);
}

namespace {

// SPH contact as a position correction: each boundary cell is moved by what its contact force
// would move it in one step, F·dt²/m, at most half the support h, and its velocity takes that move.
// A cell is a small part of a rigid fragment, so a force integrated on the cell alone (v += F/m·dt)
// is stable only for stiffness below m/dt² (≈ 5e-4 mN/mm for a level-3 cell at 120 Hz), far too
// soft to keep fragments apart; the bounded move is stable at any stiffness, and the pushed cells
// weigh heavily in the shape match, so the fragment as a whole takes the push.
void apply_contact(FragmentLens& l, FragmentLensStats& st, double dt_s) {
  std::fill(l.pushed.begin(), l.pushed.end(), uint8_t{0});
  if (l.fragments.count < 2) return;  // one body: no fragment contact to compute
  mark_boundary(l);
  const uint32_t n = l.cells.size();
  std::fill(l.fx.begin(), l.fx.end(), 0.0f);
  std::fill(l.fy.begin(), l.fy.end(), 0.0f);
  std::fill(l.fz.begin(), l.fz.end(), 0.0f);
  const sph::ContactParticles p{l.cells.x, l.cells.y, l.cells.z,         l.vx,
                                l.vy,      l.vz,      l.fragments.label, l.boundary};
  const sph::ContactStats cs = sph::fragment_contact(p, l.fragments.count, l.settings.contact,
                                                     l.contact_scratch, l.fx, l.fy, l.fz);
  st.contact_particles = cs.particles;
  st.contact_pairs = cs.pairs;
  if (cs.pairs == 0) return;
  const float max_move = 0.5f * l.settings.contact.h, inv_dt = static_cast<float>(1.0 / dt_s);
  const float dt2 = static_cast<float>(dt_s * dt_s);
  for (uint32_t c = 0; c < n; ++c) {
    if (!l.cells.alive[c] || l.cells.mass[c] <= 0) continue;
    if (l.fx[c] == 0.0f && l.fy[c] == 0.0f && l.fz[c] == 0.0f) continue;
    Vec3f d = Vec3f(l.fx[c], l.fy[c], l.fz[c]) * (dt2 / l.cells.mass[c]);  // mN·s²/kg = mm
    if (d.norm() > max_move) d *= max_move / d.norm();
    l.cells.x[c] += d.x(), l.cells.y[c] += d.y(), l.cells.z[c] += d.z();
    l.vx[c] += d.x() * inv_dt, l.vy[c] += d.y() * inv_dt, l.vz[c] += d.z() * inv_dt;
    l.pushed[c] = 1;
  }
}

void match_shapes(FragmentLens& l, FragmentLensStats& st, double dt_s) {
  const uint32_t n = l.cells.size();
  parallel_for(0, n, kCellGrain, [&](uint32_t b, uint32_t e, int) {
    for (uint32_t c = b; c < e; ++c) {
      l.current[c] = Vec3f(l.cells.x[c], l.cells.y[c], l.cells.z[c]);
      l.match_mass[c] = sph::heavy_weight(l.cells.mass[c], l.contact[c] | l.pushed[c]);
    }
  });
  const shape_match::FragmentList list{l.fragments.offsets, l.fragments.members};
  st.match = shape_match::match_lens<float>(l.rest, l.current, l.match_mass, list, l.rotations,
                                            l.settings.match);
  const float inv_dt = static_cast<float>(1.0 / dt_s);
  parallel_for(0, n, kCellGrain, [&](uint32_t b, uint32_t e, int) {
    for (uint32_t c = b; c < e; ++c) {
      if (!l.cells.alive[c]) continue;
      const Vec3f d = l.current[c] - Vec3f(l.cells.x[c], l.cells.y[c], l.cells.z[c]);
      l.cells.x[c] = l.current[c].x(), l.cells.y[c] = l.current[c].y(),
      l.cells.z[c] = l.current[c].z();
      l.vx[c] += d.x() * inv_dt, l.vy[c] += d.y() * inv_dt, l.vz[c] += d.z() * inv_dt;
    }
  });
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
  return l;
}

FragmentLensStats step_fragment_lens(FragmentLens& l, const LensTools& tools, const CounterRng& rng,
                                     uint64_t frame, double dt_s) {
  FragmentLensStats st;
  ++l.steps;
  const CellSpans cells = spans(l);
  // 2. erosion (before the lens wakes: the first removal is what wakes it)
  l.removed.clear();
  if (tools.phaco)
    lens_tools::erode(cells, *tools.phaco, l.settings.erosion, rng, frame, dt_s, l.erosion,
                      l.removed);
  if (tools.aspirator) {  // what reached the port is taken in
    const Vec3f port = tools.aspirator->port.cast<float>();
    const float r2 = static_cast<float>(l.settings.capture_mm * l.settings.capture_mm);
    const uint32_t before = static_cast<uint32_t>(l.removed.size());
    for (uint32_t c = 0; c < l.cells.size(); ++c) {
      if (!l.cells.alive[c]) continue;
      const Vec3f d = Vec3f(l.cells.x[c], l.cells.y[c], l.cells.z[c]) - port;
      if (d.squaredNorm() < r2 &&
          !std::binary_search(l.removed.begin(), l.removed.begin() + before, c))
        l.removed.push_back(c);
    }
    st.aspirated = static_cast<uint32_t>(l.removed.size()) - before;
    l.cells_aspirated += st.aspirated;
  }
  remove_lens_cells(l, l.removed, st);
  if (tools.hook || tools.aspirator) l.awake = true;
  st.fragments = l.fragments.count;
  if (!l.awake) return st;
  // 3. tools change velocities; 1. gravity and viscosity, then the move; 4. fragment contact
  if (tools.hook) lens_tools::drag_with_hook(cells, *tools.hook, l.settings.hook, dt_s);
  if (tools.aspirator) lens_tools::aspirate(cells, *tools.aspirator, l.settings.aspirator, dt_s);
  lens_tools::integrate(cells, l.settings.medium, dt_s);
  apply_contact(l, st, dt_s);
  // 5. constraints, 6. shape matching
  lens_tools::constrain(cells, l.settings.bounds, l.contact);
  match_shapes(l, st, dt_s);
  return st;
}

}  // namespace phaco::lens
