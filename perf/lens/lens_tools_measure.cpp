#include "perf/lens/lens_tools_measure.hpp"

#include <oneapi/tbb/task_arena.h>

#include <algorithm>
#include <cmath>

#include "components/lens_cells.hpp"
#include "engine/core/clock.hpp"
#include "engine/core/rng.hpp"
#include "systems/lens_tools/cell_dynamics.hpp"
#include "systems/lens_tools/constraints.hpp"
#include "systems/lens_tools/erosion.hpp"

namespace phaco::perf {

namespace {

// The standard lens (DESIGN.md §6): equator radius 4.7, anterior half-thickness 1.8, posterior
// 2.7; nucleus the inner 70 %. Density 1.1e-6 kg/mm³.
constexpr double kEquator = 4.7, kAnterior = 1.8, kPosterior = 2.7, kNucleus = 0.7;

LensCells lens_cells(uint32_t n) {
  LensCells c;
  c.resize(n);
  const CounterRng rng(2026, 9);
  const double volume = 2.0 / 3.0 * M_PI * kEquator * kEquator * (kAnterior + kPosterior);
  const float mass = static_cast<float>(1.1e-6 * volume / n);
  uint32_t draw = 0;
  for (uint32_t i = 0; i < n; ++i) {
    for (;;) {  // rejection sampling in the bounding box; deterministic
      const double x = (2 * rng.uniform_double(i, draw, 0) - 1) * kEquator;
      const double y = (2 * rng.uniform_double(i, draw, 1) - 1) * kEquator;
      const double z = -kPosterior + (kAnterior + kPosterior) * rng.uniform_double(i, draw, 2);
      ++draw;
      const double h = z >= 0 ? kAnterior : kPosterior;
      const double s = (x * x + y * y) / (kEquator * kEquator) + z * z / (h * h);
      if (s > 1) continue;
      c.x[i] = static_cast<float>(x), c.y[i] = static_cast<float>(y),
      c.z[i] = static_cast<float>(z);
      c.hardness[i] = std::sqrt(s) < kNucleus ? 0.7f : 0.2f;
      break;
    }
    c.mass[i] = mass;
  }
  return c;
}

struct PartTimes {
  double erosion = 0, aspirate = 0, hook = 0, integrate = 0, constrain = 0;
  double total() const { return erosion + aspirate + hook + integrate + constrain; }
};

}  // namespace

std::vector<LensToolsRow> measure_lens_tools(std::span<const uint32_t> cell_counts,
                                             std::span<const int> threads, uint32_t frames,
                                             uint32_t warmup, int repeats) {
  using namespace lens_tools;
  std::vector<LensToolsRow> rows;
  const double dt = 1.0 / 120;
  const EyeBounds bounds = eye_bounds(kEquator, kAnterior, -kPosterior, 4.8, 6.5, 2.6);
  ErosionSettings erosion;
  AspiratorSettings aspirator;
  HookSettings hook_settings;
  // No gravity: shape matching (not timed here) is what holds the lens's shape; without it the
  // cells, independent points, would sink into the posterior cap within 0.1 s and every frame would
  // be a pile-up on the capsule, not the scene the trainer runs.
  Medium medium;
  medium.gravity.setZero();
  for (uint32_t n : cell_counts) {
    const LensCells initial = lens_cells(n);
    for (int t : threads) {
      LensToolsRow row;
      row.cells = n, row.threads = t, row.frames = frames;
      PartTimes best;
      best.erosion = 1e300;
      double best_total = 1e300;
      tbb::task_arena arena(std::max(t, 1));
      for (int r = 0; r < std::max(repeats, 1); ++r) {
        LensCells c = initial;
        ErosionScratch scratch;
        std::vector<uint32_t> removed;
        removed.reserve(n);
        PartTimes sum;
        uint64_t removed_total = 0;
        arena.execute([&] {
          for (uint32_t f = 0; f < warmup + frames; ++f) {
            const double time = f * dt;
            PhacoTip tip;
            tip.apex = Vec3(0.0, -1.0 + 1.0 * time, 1.9 - 0.5 * time);
            tip.axis = Vec3(0, 0.3, -1).normalized();
            tip.power = 0.6;
            const Aspirator asp{tip.apex, 300.0};  // the phaco tip aspirates through its port
            Hook hook;
            hook.a = hook.bend = Vec3(-1.5 + 0.8 * time, 0.5, 1.2);
            hook.b = hook.a + Vec3(0, 0, 1.0);
            hook.velocity = Vec3(0.8, 0, 0);
            const CellSpans cells = cell_spans(c);
            const bool timed = f >= warmup;
            Stopwatch clock;
            erode(cells, tip, erosion, CounterRng(7, 1), f, dt, scratch, removed);
            // The simplex system would remove them in the topology phase; here: clear alive.
            for (uint32_t id : removed) c.alive[id] = 0;
            const double t_erosion = clock.elapsed_ms();
            clock.restart();
            aspirate(cells, asp, aspirator, dt);
            const double t_aspirate = clock.elapsed_ms();
            clock.restart();
            drag_with_hook(cells, hook, hook_settings, dt);
            const double t_hook = clock.elapsed_ms();
            clock.restart();
            integrate(cells, medium, dt);
            const double t_integrate = clock.elapsed_ms();
            clock.restart();
            constrain(cells, bounds, c.contact);
            const double t_constrain = clock.elapsed_ms();
            if (!timed) continue;
            sum.erosion += t_erosion, sum.aspirate += t_aspirate, sum.hook += t_hook;
            sum.integrate += t_integrate, sum.constrain += t_constrain;
            removed_total += removed.size();
          }
        });
        if (sum.total() < best_total) {
          best_total = sum.total();
          best = sum;
          row.removed_per_frame = static_cast<double>(removed_total) / frames;
        }
      }
      const double per = 1.0 / std::max<uint32_t>(frames, 1);
      row.erosion_ms = best.erosion * per, row.aspirate_ms = best.aspirate * per;
      row.hook_ms = best.hook * per, row.integrate_ms = best.integrate * per;
      row.constrain_ms = best.constrain * per;
      row.ms_per_frame = best.total() * per;
      rows.push_back(row);
    }
  }
  return rows;
}

}  // namespace phaco::perf
