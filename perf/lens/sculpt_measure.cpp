#include "perf/lens/sculpt_measure.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>

#include "components/tet_topology.hpp"
#include "procedures/eye/eye_geometry.hpp"
#include "procedures/eye/eye_mesh.hpp"
#include "procedures/eye/eye_params.hpp"
#include "procedures/eye/mesh_cache.hpp"
#include "systems/sculpt/swept_volume.hpp"

namespace phaco::perf {

std::vector<Vec3> standard_sculpt_path() {
  return {Vec3(-3.0, 0.0, 2.6), Vec3(-3.0, 0.0, 1.2), Vec3(3.0, 0.0, 1.2), Vec3(3.0, 0.1, 0.7),
          Vec3(-3.0, 0.1, 0.7), Vec3(-3.0, 0.0, 0.2), Vec3(3.0, 0.0, 0.2), Vec3(3.0, 0.0, 2.6)};
}

namespace {

using Clock = std::chrono::steady_clock;

double percentile(std::vector<double> v, double q) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  const size_t i = std::min(v.size() - 1, static_cast<size_t>(std::ceil(q * v.size())) - 1);
  return v[i];
}

std::vector<sculpt::SculptTip> sample(const std::vector<Vec3>& path, double radius, double step) {
  std::vector<sculpt::SculptTip> track;
  track.push_back({path[0], path[0], radius});
  for (size_t i = 0; i + 1 < path.size(); ++i) {
    const int n = std::max(1, static_cast<int>(std::ceil((path[i + 1] - path[i]).norm() / step)));
    for (int k = 1; k <= n; ++k)
      track.push_back({path[i] + (path[i + 1] - path[i]) * (static_cast<double>(k) / n),
                       track.back().centre, radius});
  }
  return track;
}

}  // namespace

std::vector<SculptMeasureRow> measure_sculpt(const SculptMeasureOptions& options) {
  const eye::EyeParams params = eye::default_eye_params();
  const eye::EyeGeometry g = eye::eye_geometry(params);
  const sculpt::LensShape lens{g.lens_a, g.lens_c_anterior, g.lens_c_posterior};
  const std::vector<Vec3> path = standard_sculpt_path();
  const auto track = sample(path, options.radius_mm, options.step_mm);
  const sculpt::SweptVolume reference =
      sculpt::swept_volume_in_lens(path, options.radius_mm, lens, options.reference_column_mm);

  std::vector<SculptMeasureRow> rows;
  for (int level : options.levels) {
    const eye::Resolution res = eye::resolution_for_level(level);
    TetMesh mesh;
    if (options.use_mesh_cache) {
      eye::MeshCache cache(eye::MeshCache::default_dir());
      mesh = std::move(
          *cache.load_or_build(params, res, eye::CapsuleLayout::Curvilinear, true).lens_tets);
    } else {
      mesh = eye::make_lens_tets(params, res);
    }
    for (sculpt::Broadphase bp : options.broadphases) {
      for (sculpt::Narrowphase np : options.narrowphases) {
        SculptMeasureRow row;
        row.level = level;
        row.broadphase = sculpt::to_string(bp);
        row.narrowphase = sculpt::to_string(np);
        row.tets = static_cast<uint32_t>(mesh.tets.size());
        const auto t0 = Clock::now();
        TetTopology topo = build_tet_topology(mesh);
        sculpt::SculptOptions so;
        so.broadphase = bp;
        so.narrowphase = np;
        sculpt::SculptState state = sculpt::make_sculpt_state(topo, so);
        row.build_ms = std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
        std::vector<double> us;
        us.reserve(track.size());
        double work = 0, broad = 0;
        for (const auto& tip : track) {
          const auto s0 = Clock::now();
          const auto removed = sculpt::sculpt_step(topo, mesh.vertices, state, tip);
          us.push_back(std::chrono::duration<double, std::micro>(Clock::now() - s0).count());
          for (uint32_t t : removed) row.removed_mm3 += topo.volume[t];
          row.removed_tets += static_cast<uint32_t>(removed.size());
          work += state.stats.work();
          broad += state.stats.used_broadphase ? 1 : 0;
        }
        row.steps = static_cast<uint32_t>(track.size());
        row.step_p50_us = percentile(us, 0.50);
        row.step_p99_us = percentile(us, 0.99);
        row.step_max_us = *std::max_element(us.begin(), us.end());
        row.mean_work = work / row.steps;
        row.broadphase_steps = broad / row.steps;
        row.reference_mm3 = reference.volume_mm3;
        row.reference_error_mm3 = reference.error_mm3;
        row.relative_error = row.removed_mm3 / reference.volume_mm3 - 1.0;
        rows.push_back(row);
      }
    }
  }
  return rows;
}

}  // namespace phaco::perf
