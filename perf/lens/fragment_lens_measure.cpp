#include "perf/lens/fragment_lens_measure.hpp"

#include <oneapi/tbb/task_arena.h>

#include <chrono>
#include <cmath>

#include "procedures/eye/eye_mesh.hpp"
#include "procedures/lens/fragment_lens.hpp"

namespace phaco::perf {
namespace {

lens::FragmentLensSettings standard_settings(double mean_tet_volume) {
  lens::FragmentLensSettings s;
  s.bounds = lens_tools::eye_bounds(4.7, 1.8, -2.7, 4.8, 6.5, 2.6);
  s.contact.h = static_cast<float>(1.5 * std::cbrt(mean_tet_volume));
  return s;
}

// Slabs 2.5 cell sizes thick at x, y = k·9.4/(cuts+1) − 4.7: (cuts+1)² pieces.
std::vector<uint32_t> slab_cells(const lens::FragmentLens& l, int cuts, double thickness) {
  std::vector<uint32_t> out;
  if (cuts <= 0) return out;
  for (uint32_t c = 0; c < l.cells.size(); ++c) {
    for (int k = 1; k <= cuts; ++k) {
      const double p = -4.7 + 9.4 * k / (cuts + 1);
      if (std::abs(l.cells.rest_x[c] - p) < thickness ||
          std::abs(l.cells.rest_y[c] - p) < thickness) {
        out.push_back(c);
        break;
      }
    }
  }
  return out;
}

}  // namespace

std::vector<FragmentLensRow> measure_fragment_lens(std::span<const int> levels,
                                                   std::span<const int> cuts,
                                                   std::span<const int> threads, uint32_t frames,
                                                   int repeats) {
  std::vector<FragmentLensRow> rows;
  for (int level : levels) {
    const TetMesh mesh =
        eye::make_lens_tets(eye::default_eye_params(), eye::resolution_for_level(level));
    double volume = 0;
    for (const auto& t : mesh.tets) {
      const Vec3 &a = mesh.vertices[t[0]], &b = mesh.vertices[t[1]], &c = mesh.vertices[t[2]],
                 &d = mesh.vertices[t[3]];
      volume += (b - a).dot((c - a).cross(d - a)) / 6.0;
    }
    const double mean_volume = volume / double(mesh.tets.size());
    for (int k : cuts) {
      for (int th : threads) {
        FragmentLensRow row;
        row.level = level, row.threads = th, row.frames = frames;
        row.ms_per_frame = 1e300;
        for (int rep = 0; rep < repeats; ++rep) {
          tbb::task_arena(th).execute([&] {
            lens::FragmentLens l = lens::make_fragment_lens(mesh, standard_settings(mean_volume));
            lens::FragmentLensStats st;
            lens::remove_lens_cells(l, slab_cells(l, k, 1.25 * std::cbrt(mean_volume)), st);
            l.awake = true;
            const CounterRng rng(1);
            for (uint64_t f = 0; f < 5; ++f)
              lens::step_fragment_lens(l, {}, rng, f, 1.0 / 120);  // warm-up
            double pairs = 0, particles = 0;
            const auto t0 = std::chrono::steady_clock::now();
            for (uint64_t f = 0; f < frames; ++f) {
              const lens::FragmentLensStats s =
                  lens::step_fragment_lens(l, {}, rng, 5 + f, 1.0 / 120);
              pairs += double(s.contact_pairs), particles += s.contact_particles;
            }
            const double ms =
                std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0)
                    .count();
            row.ms_per_frame = std::min(row.ms_per_frame, ms / frames);
            row.cells = l.cells.alive_count;
            row.fragments = l.fragments.count;
            row.contact_pairs = pairs / frames, row.contact_particles = particles / frames;
          });
        }
        rows.push_back(row);
      }
    }
  }
  return rows;
}

}  // namespace phaco::perf
