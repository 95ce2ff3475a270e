#include "perf/lens/simplex_measure.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <random>

#include "engine/core/clock.hpp"
#include "perf/timing.hpp"
#include "procedures/eye/eye_mesh.hpp"
#include "procedures/eye/eye_params.hpp"
#include "procedures/eye/resolution.hpp"
#include "systems/simplex/simplex_cells.hpp"
#include "systems/simplex/simplex_fragments.hpp"
#include "systems/simplex/simplex_surface.hpp"

namespace phaco::perf {
namespace {

struct Stats {
  double mean_us = 0.0, p99_us = 0.0;
};

Stats stats_of(std::vector<double>& us) {
  Stats s;
  if (us.empty()) return s;
  s.mean_us = std::accumulate(us.begin(), us.end(), 0.0) / static_cast<double>(us.size());
  const size_t k = std::min(
      us.size() - 1, static_cast<size_t>(std::ceil(0.99 * static_cast<double>(us.size()))) - 1);
  std::nth_element(us.begin(), us.begin() + static_cast<std::ptrdiff_t>(k), us.end());
  s.p99_us = us[k];
  return s;
}

// Cells by distance from the anterior pole: a crater growing into the lens.
std::vector<uint32_t> crater_order(const SimplexCells& cells) {
  std::vector<uint32_t> order(cells.size());
  std::iota(order.begin(), order.end(), 0u);
  auto d2 = [&](uint32_t c) {
    const double z = cells.rest_z[c] - 1.8;
    return double(cells.rest_x[c]) * cells.rest_x[c] + double(cells.rest_y[c]) * cells.rest_y[c] +
           z * z;
  };
  std::stable_sort(order.begin(), order.end(),
                   [&](uint32_t a, uint32_t b) { return d2(a) < d2(b); });
  return order;
}

std::vector<uint32_t> random_order(uint32_t n, uint32_t seed) {
  std::vector<uint32_t> order(n);
  std::iota(order.begin(), order.end(), 0u);
  std::mt19937 rng(seed);
  for (uint32_t i = n; i > 1; --i) std::swap(order[i - 1], order[rng() % i]);
  return order;
}

}  // namespace

std::vector<SimplexRow> measure_simplex(const SimplexMeasureOptions& options) {
  std::vector<SimplexRow> rows;
  for (int level : options.levels) {
    const TetMesh mesh =
        eye::make_lens_tets(eye::default_eye_params(), eye::resolution_for_level(level));
    SimplexRow row;
    row.level = level;
    SimplexCells cells;
    row.build_ms = 1e3 * seconds_per_call(
                             1, options.min_seconds, options.repeats,
                             [&] { cells = simplex::build_cells(mesh); }, 1);
    row.cells = cells.size();
    row.external_faces = simplex::count_external_faces(cells);
    const uint32_t removals = std::min(options.removals, row.cells / 4);

    std::vector<std::array<uint32_t, 12>> links;
    row.rebuild_links_ms = 1e3 * seconds_per_call(1, options.min_seconds, options.repeats, [&] {
                             simplex::rebuild_boundary_links(cells, links);
                           });
    row.check_ms = 1e3 * seconds_per_call(1, options.min_seconds, options.repeats,
                                          [&] { (void)simplex::check_boundary(cells); });
    simplex::BoundarySurface surface;
    row.surface_ms = 1e3 * seconds_per_call(1, options.min_seconds, options.repeats, [&] {
                       simplex::build_boundary_surface(cells, surface);
                     });
    SurfaceMesh faces;
    row.extract_ms = 1e3 * seconds_per_call(1, options.min_seconds, options.repeats, [&] {
                       simplex::extract_external_faces(cells, mesh.vertices, faces);
                     });

    Fragments frags;
    simplex::FragmentScratch scratch;
    auto time_labelling = [&](const SimplexCells& c, double& paint, double& uf1, double& uf2) {
      paint = 1e3 * seconds_per_call(1, options.min_seconds, options.repeats,
                                     [&] { simplex::label_fragments_painting(c, frags, scratch); });
      uf1 = 1e3 * seconds_per_call(1, options.min_seconds, options.repeats, [&] {
              simplex::label_fragments_union_find(c, frags, scratch, options.union_find_grain);
            });
      uf2 = 1e3 * seconds_per_call(2, options.min_seconds, options.repeats, [&] {
              simplex::label_fragments_union_find(c, frags, scratch, options.union_find_grain);
            });
    };
    time_labelling(cells, row.paint_ms, row.union_find_1t_ms, row.union_find_2t_ms);

    // Crater: each removal timed alone, then the fragment update it triggers.
    {
      SimplexCells work = cells;
      simplex::label_fragments_painting(work, frags, scratch);
      const auto order = crater_order(work);
      std::vector<double> remove_us, update_us;
      uint32_t relabels = 0;
      for (uint32_t i = 0; i < removals; ++i) {
        const int64_t t0 = now_ns();
        simplex::Removal r = simplex::remove_cell(work, order[i]);
        const int64_t t1 = now_ns();
        simplex::confirm_split(work, r, scratch);
        relabels += simplex::update_fragments(work, std::span<const simplex::Removal>(&r, 1), frags,
                                              scratch)
                        .relabelled;
        const int64_t t2 = now_ns();
        remove_us.push_back(1e-3 * static_cast<double>(t1 - t0));
        update_us.push_back(1e-3 * static_cast<double>(t2 - t1));
      }
      const Stats s = stats_of(remove_us);
      row.crater_mean_us = s.mean_us, row.crater_p99_us = s.p99_us;
      row.update_mean_us = stats_of(update_us).mean_us;
      row.update_relabel_fraction = removals ? static_cast<double>(relabels) / removals : 0.0;
    }
    // Scattered: random cells; then half the lens removed for the shattered labelling.
    {
      SimplexCells work = cells;
      const auto order = random_order(work.size(), options.seed);
      std::vector<double> remove_us;
      for (uint32_t i = 0; i < removals; ++i) {
        const int64_t t0 = now_ns();
        simplex::remove_cell(work, order[i]);
        remove_us.push_back(1e-3 * static_cast<double>(now_ns() - t0));
      }
      const Stats s = stats_of(remove_us);
      row.scattered_mean_us = s.mean_us, row.scattered_p99_us = s.p99_us;
      for (uint32_t i = removals; i < work.size() / 2; ++i) simplex::remove_cell(work, order[i]);
      time_labelling(work, row.shattered_paint_ms, row.shattered_union_find_1t_ms,
                     row.shattered_union_find_2t_ms);
      row.shattered_fragments = frags.count;
    }
    rows.push_back(row);
  }
  return rows;
}

}  // namespace phaco::perf
