// One sculpt step (broadphase or walk + removal + surface update) on the lens at levels 0, 3, 5:
// the tip runs a straight stroke through the lens, a fresh lens whenever the stroke ends.
#include <benchmark/benchmark.h>

#include <map>

#include "components/tet_topology.hpp"
#include "procedures/eye/eye_mesh.hpp"
#include "procedures/eye/eye_params.hpp"
#include "systems/sculpt/sculpt.hpp"

namespace {

using namespace phaco;

const TetMesh& lens(int level) {
  static std::map<int, TetMesh> cache;
  auto it = cache.find(level);
  if (it == cache.end())
    it = cache
             .emplace(level, eye::make_lens_tets(eye::default_eye_params(),
                                                 eye::resolution_for_level(level)))
             .first;
  return it->second;
}

void BM_SculptStep(benchmark::State& st) {
  const int level = static_cast<int>(st.range(0));
  sculpt::SculptOptions options;
  options.broadphase = st.range(1) == 0 ? sculpt::Broadphase::Octree : sculpt::Broadphase::Dbvt;
  options.narrowphase = static_cast<sculpt::Narrowphase>(st.range(2));
  const TetMesh& mesh = lens(level);
  const Vec3 from(-3.0, 0.0, 0.6), to(3.0, 0.0, 0.6);
  constexpr int kSteps = 150;  // 0.04 mm per step
  TetTopology topo = build_tet_topology(mesh);
  sculpt::SculptState state = sculpt::make_sculpt_state(topo, options);
  int step = 0;
  Vec3 prev = from;
  uint64_t removed = 0;
  for (auto _ : st) {
    if (step == kSteps) {
      st.PauseTiming();
      topo = build_tet_topology(mesh);
      state = sculpt::make_sculpt_state(topo, options);
      step = 0;
      prev = from;
      st.ResumeTiming();
    }
    const Vec3 p = from + (to - from) * (static_cast<double>(++step) / kSteps);
    removed += sculpt::sculpt_step(topo, mesh.vertices, state, {p, prev, sculpt::kPhacoTipRadiusMm})
                   .size();
    prev = p;
  }
  st.counters["tets"] = static_cast<double>(mesh.tets.size());
  st.counters["removed/step"] =
      benchmark::Counter(static_cast<double>(removed), benchmark::Counter::kAvgIterations);
}

// Args: level, broadphase (0 octree, 1 dbvt), narrowphase (0 centre, 1 gjk, 2 mpr).
BENCHMARK(BM_SculptStep)->ArgsProduct({{0, 3, 5}, {0, 1}, {0, 1}})->Unit(benchmark::kMicrosecond);

}  // namespace
