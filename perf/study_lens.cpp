// phaco-perf lens (issue 5): the phaco-sculpting half of the physics. Tetrahedral sculpting per
// level × broadphase × narrowphase against the exact swept volume; the simplex cells' removal,
// boundary and fragment labelling; shape matching (Horn against polar decomposition on degenerate
// fragments, float against double, cost per fragment size, the whole-lens pass); the SPH
// neighbour search per cell order; the lens tools; the fragmenting lens per frame; and the
// divide-and-conquer demo in the scene per level. Measurements live in perf/lens/; this file
// sweeps, tabulates, charts and writes the section.
#include <algorithm>
#include <cmath>
#include <map>
#include <string>
#include <vector>

#include "engine/core/error.hpp"
#include "engine/io/scenario.hpp"
#include "perf/lens/fragment_lens_measure.hpp"
#include "perf/lens/lens_tools_measure.hpp"
#include "perf/lens/sculpt_measure.hpp"
#include "perf/lens/shape_match_measure.hpp"
#include "perf/lens/simplex_measure.hpp"
#include "perf/lens/sph_measure.hpp"
#include "perf/plot.hpp"
#include "perf/report.hpp"
#include "perf/studies.hpp"
#include "procedures/scene/run.hpp"

namespace phaco::perf {
namespace {

struct LensSceneRow {
  int level = 0;
  double tets = 0, frames = 0, frame_p50_ms = 0, frame_p99_ms = 0, sculpt_p50_ms = 0,
         sculpt_p99_ms = 0;
  double step_mean_ms = 0, step_max_ms = 0, removed = 0, volume_mm3 = 0, rotation_deg = 0;
  double trenches = 0, width0 = 0, width1 = 0, depth0 = 0, depth1 = 0, crossing_deg = 0;
};

LensSceneRow measure_scene(int level) {
  Scenario s = load_scenario(std::filesystem::path(PHACO_SOURCE_DIR) /
                             "data/scenarios/phaco_sculpting_demo.json");
  s.eye.level = level;
  const RunReport r = run_scenario(s, SceneOptions{});
  LensSceneRow row;
  row.level = level;
  row.frames = double(r.frames);
  row.frame_p50_ms = r.frame.p50_ms, row.frame_p99_ms = r.frame.p99_ms;
  for (const auto& c : r.systems)
    if (c.name == "lens_sculpt") row.sculpt_p50_ms = c.p50_ms, row.sculpt_p99_ms = c.p99_ms;
  const nlohmann::json j = r.physics.value("lens_sculpting", nlohmann::json::object());
  row.tets = j.value("tets", 0.0);
  row.step_mean_ms = j.value("sculpt_ms_mean", 0.0),
  row.step_max_ms = j.value("sculpt_ms_max", 0.0);
  row.removed = j.value("tets_removed", 0.0), row.volume_mm3 = j.value("volume_removed_mm3", 0.0);
  row.rotation_deg = j.value("nucleus_rotation_deg", 0.0);
  row.trenches = j.value("trench_count", 0.0);
  row.crossing_deg = j.value("trench_crossing_angle_deg", 0.0);
  const auto t = j.value("trenches", nlohmann::json::array());
  if (t.size() > 0)
    row.width0 = t[0].value("width_mm", 0.0), row.depth0 = t[0].value("depth_fraction", 0.0);
  if (t.size() > 1)
    row.width1 = t[1].value("width_mm", 0.0), row.depth1 = t[1].value("depth_fraction", 0.0);
  return row;
}

std::string yes_no(bool b) {
  return b ? "yes" : "no";
}

double per_step(const SculptMeasureRow& r) {
  return r.steps ? double(r.removed_tets) / r.steps : 0.0;
}

std::string sculpt_section(const std::vector<SculptMeasureRow>& rows,
                           const std::filesystem::path& dir) {
  Table t;
  t.columns = {"level",       "broadphase",       "narrowphase",         "tets",
               "steps",       "build_ms",         "step_p50_us",         "step_p99_us",
               "step_max_us", "broadphase_steps", "mean_work",           "removed_tets",
               "removed_mm3", "reference_mm3",    "reference_error_mm3", "relative_error"};
  for (const auto& r : rows)
    t.add({double(r.level), r.broadphase, r.narrowphase, double(r.tets), double(r.steps),
           r.build_ms, r.step_p50_us, r.step_p99_us, r.step_max_us, r.broadphase_steps, r.mean_work,
           double(r.removed_tets), r.removed_mm3, r.reference_mm3, r.reference_error_mm3,
           r.relative_error});
  write_csv(t, dir / "lens_sculpt.csv");
  write_json(t, dir / "lens_sculpt.json");

  Chart cost{.title = "Sculpt step (broadphase + removal + surface update) against lens size",
             .x = {"lens tets", Scale::Log10},
             .y = {"us per step (p50)", Scale::Log10}};
  Chart error{.title = "Removed volume against the exact swept volume",
              .x = {"lens tets", Scale::Log10},
              .y = {"|removed / exact - 1|", Scale::Log10}};
  std::map<std::string, Series> cs, es;
  for (const auto& r : rows) {
    const std::string key = r.broadphase + " + " + r.narrowphase;
    auto& c = cs[key];
    c.name = key, c.fit_power_law = true;
    c.x.push_back(r.tets), c.y.push_back(r.step_p50_us);
    if (r.broadphase == "octree" && r.narrowphase == "centre") {
      auto& pt = cs["octree + centre, per tet removed"];
      pt.name = "octree + centre, per tet removed", pt.fit_power_law = true, pt.dashed = true;
      pt.x.push_back(r.tets), pt.y.push_back(r.step_p50_us / std::max(1e-9, per_step(r)));
    }
    if (r.broadphase == "octree") {
      auto& e = es[r.narrowphase];
      e.name = r.narrowphase;
      e.x.push_back(r.tets), e.y.push_back(std::max(1e-4, std::abs(r.relative_error)));
    }
  }
  for (auto& [k, s] : cs) cost.series.push_back(s);
  for (auto& [k, s] : es) error.series.push_back(s);
  cost.markers = {{"target 200 us", 50000, 200}, {"target 400 us", 1000000, 400}};
  save_chart(cost, dir / "lens_sculpt_cost.png");
  save_chart(error, dir / "lens_sculpt_error.png");

  std::string md =
      "### Tetrahedral sculpting (seed 000 §5.3)\n\n"
      "`perf/lens/sculpt_measure`: the standard sweep (three trench strokes along x at falling "
      "depth, "
      "tip radius 0.45 mm, 0.04 mm per step), one step = broadphase (only when the tip has no last "
      "removals to continue from) + narrowphase + removal + surface-list update. The reference is "
      "the "
      "exact volume of the swept tip inside the lens (closed form along z, numerical in x-y at two "
      "spacings, error estimate given). p50 is the figure to trust; p99/max include preemption.\n\n"
      "A finer lens has more tets under the same tip, so a step removes more of them; the "
      "locality figure is the time per tet removed (p50 step time over the mean removals per "
      "step).\n\n"
      "| level | broadphase | narrowphase | tets | build (ms) | step p50 / p99 / max (us) | tets "
      "removed per step | us per tet removed | broadphase steps | removed (mm3) | exact (mm3) | "
      "error |\n|---:|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n";
  for (const auto& r : rows) {
    md += "| " + std::to_string(r.level) + " | " + r.broadphase + " | " + r.narrowphase + " | " +
          std::to_string(r.tets) + " | " + fmt("%.1f", r.build_ms) + " | " +
          fmt("%.1f", r.step_p50_us) + " / " + fmt("%.1f", r.step_p99_us) + " / " +
          fmt("%.0f", r.step_max_us) + " | " + fmt("%.1f", per_step(r)) + " | " +
          fmt("%.2f", r.step_p50_us / std::max(1e-9, per_step(r))) + " | " +
          fmt("%.1f %%", 100 * r.broadphase_steps) + " | " + fmt("%.3f", r.removed_mm3) + " | " +
          fmt("%.3f", r.reference_mm3) + " ± " + fmt("%.3f", r.reference_error_mm3) + " | " +
          fmt("%+.1f %%", 100 * r.relative_error) + " |\n";
  }
  for (auto& s : cost.series) {
    const PowerFit f = fit_power_law(s.x, s.y);
    md += "\nSlope of step time against tets, " + s.name + ": " + fmt("%.2f", f.slope) + ".";
  }
  md +=
      "\n\n![sculpt cost](results/lens_sculpt_cost.png)\n![sculpt "
      "error](results/lens_sculpt_error.png)\n\n";
  return md;
}

std::string simplex_section(const std::vector<SimplexRow>& rows, const std::filesystem::path& dir) {
  Table t;
  t.columns = {"level",
               "cells",
               "external_faces",
               "build_ms",
               "crater_mean_us",
               "crater_p99_us",
               "scattered_mean_us",
               "scattered_p99_us",
               "rebuild_links_ms",
               "check_ms",
               "surface_ms",
               "extract_ms",
               "paint_ms",
               "union_find_1t_ms",
               "union_find_2t_ms",
               "shattered_fragments",
               "shattered_paint_ms",
               "shattered_union_find_1t_ms",
               "shattered_union_find_2t_ms",
               "update_mean_us",
               "update_relabel_fraction"};
  for (const auto& r : rows)
    t.add({double(r.level),
           double(r.cells),
           double(r.external_faces),
           r.build_ms,
           r.crater_mean_us,
           r.crater_p99_us,
           r.scattered_mean_us,
           r.scattered_p99_us,
           r.rebuild_links_ms,
           r.check_ms,
           r.surface_ms,
           r.extract_ms,
           r.paint_ms,
           r.union_find_1t_ms,
           r.union_find_2t_ms,
           double(r.shattered_fragments),
           r.shattered_paint_ms,
           r.shattered_union_find_1t_ms,
           r.shattered_union_find_2t_ms,
           r.update_mean_us,
           r.update_relabel_fraction});
  write_csv(t, dir / "lens_simplex.csv");
  write_json(t, dir / "lens_simplex.json");
  Chart c{.title = "Simplex cells: removal and whole-lens passes against size",
          .x = {"cells", Scale::Log10},
          .y = {"us", Scale::Log10}};
  Series rm{"removal (crater), mean"}, up{"fragment update after a removal"},
      paint{"painting, whole lens"}, surf{"boundary surface, whole lens"};
  rm.fit_power_law = up.fit_power_law = paint.fit_power_law = surf.fit_power_law = true;
  for (const auto& r : rows) {
    rm.x.push_back(r.cells), rm.y.push_back(r.crater_mean_us);
    up.x.push_back(r.cells), up.y.push_back(r.update_mean_us);
    paint.x.push_back(r.cells), paint.y.push_back(1e3 * r.paint_ms);
    surf.x.push_back(r.cells), surf.y.push_back(1e3 * r.surface_ms);
  }
  c.series = {rm, up, paint, surf};
  save_chart(c, dir / "lens_simplex.png");
  std::string md =
      "### Simplex cells and fragments (seed 002 §5)\n\n"
      "`perf/lens/simplex_measure`: construction by the seed's three loops, the removal primitive "
      "per "
      "cell (a crater from the anterior pole: the seed's cases; scattered random cells: cavities), "
      "the "
      "boundary checked against a rebuild, the dual surface, and fragment labelling by painting "
      "and by "
      "the parallel union-find (same labels).\n\n"
      "| level | cells | build (ms) | removal crater mean / p99 (us) | scattered mean / p99 (us) | "
      "surface (ms) | paint (ms) | union-find 1t / 2t (ms) | shattered: fragments, paint / UF 1t / "
      "2t "
      "(ms) | update after removal (us) | relabels |\n"
      "|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n";
  for (const auto& r : rows) {
    md += "| " + std::to_string(r.level) + " | " + std::to_string(r.cells) + " | " +
          fmt("%.1f", r.build_ms) + " | " + fmt("%.2f", r.crater_mean_us) + " / " +
          fmt("%.2f", r.crater_p99_us) + " | " + fmt("%.2f", r.scattered_mean_us) + " / " +
          fmt("%.2f", r.scattered_p99_us) + " | " + fmt("%.2f", r.surface_ms) + " | " +
          fmt("%.2f", r.paint_ms) + " | " + fmt("%.2f", r.union_find_1t_ms) + " / " +
          fmt("%.2f", r.union_find_2t_ms) + " | " + std::to_string(r.shattered_fragments) + ": " +
          fmt("%.2f", r.shattered_paint_ms) + " / " + fmt("%.2f", r.shattered_union_find_1t_ms) +
          " / " + fmt("%.2f", r.shattered_union_find_2t_ms) + " | " +
          fmt("%.1f", r.update_mean_us) + " | " + fmt("%.1f %%", 100 * r.update_relabel_fraction) +
          " |\n";
  }
  md += "\n![simplex](results/lens_simplex.png)\n\n";
  return md;
}

std::string shape_section(const std::vector<ShapeDegenerateRow>& deg,
                          const std::vector<ShapePrecisionRow>& prec,
                          const std::vector<ShapeTimingRow>& timing,
                          const std::vector<ShapeLensRow>& lens, const std::filesystem::path& dir) {
  Table t;
  t.columns = {"case",           "method",  "trials",      "max_angle_deg",
               "mean_angle_deg", "min_det", "max_goal_mm", "flagged"};
  for (const auto& r : deg)
    t.add({r.case_name, r.method, double(r.trials), r.max_angle_deg, r.mean_angle_deg, r.min_det,
           r.max_goal_mm, double(r.flagged)});
  write_csv(t, dir / "lens_shape_degenerate.csv");
  Table tt;
  tt.columns = {"method", "cells", "ns_per_fragment", "ns_solve"};
  for (const auto& r : timing) tt.add({r.method, double(r.cells), r.ns_per_fragment, r.ns_solve});
  write_csv(tt, dir / "lens_shape_timing.csv");
  write_json(tt, dir / "lens_shape_timing.json");

  Chart c{.title = "Shape matching: one fragment (moments + solve)",
          .x = {"cells in the fragment", Scale::Log10},
          .y = {"ns per fragment", Scale::Log10}};
  std::map<std::string, Series> by;
  for (const auto& r : timing) {
    auto& s = by[r.method];
    s.name = r.method;
    s.x.push_back(r.cells), s.y.push_back(r.ns_per_fragment);
  }
  for (auto& [k, s] : by) c.series.push_back(s);
  c.markers = {{"target 500 ns (4 cells)", 4, 500}};
  save_chart(c, dir / "lens_shape_timing.png");

  std::string md =
      "### Shape matching (seed 002 §6.2): Horn's closed form against polar decomposition\n\n"
      "`perf/lens/shape_match_measure`. Degenerate fragments over random rigid transforms: the "
      "angle "
      "between the recovered and the true rotation (where the rotation is undetermined, any answer "
      "is "
      "as good; the point is det and continuity), the smallest determinant returned, and the "
      "largest "
      "goal-position error.\n\n| case | method | trials | max angle (deg) | mean angle (deg) | min "
      "det | "
      "max goal error (mm) | flagged |\n|---|---|---:|---:|---:|---:|---:|---:|\n";
  for (const auto& r : deg) {
    md += "| " + r.case_name + " | " + r.method + " | " + std::to_string(r.trials) + " | " +
          fmt("%.3g", r.max_angle_deg) + " | " + fmt("%.3g", r.mean_angle_deg) + " | " +
          fmt("%.3f", r.min_det) + " | " + fmt("%.3g", r.max_goal_mm) + " | " +
          std::to_string(r.flagged) + " |\n";
  }
  md +=
      "\nFloat against double on nearly collinear clusters (cells `offset` off a 4 mm line):\n\n"
      "| offset (mm) | cells | method | trials | max angle (deg) | median gap "
      "|\n|---:|---:|---|---:|---:|---:|\n";
  for (const auto& r : prec) {
    md += "| " + fmt("%.0e", r.offset_mm) + " | " + std::to_string(r.cells) + " | " + r.method +
          " | " + std::to_string(r.trials) + " | " + fmt("%.3g", r.max_angle_deg) + " | " +
          fmt("%.2e", r.median_gap) + " |\n";
  }
  md +=
      "\nCost of one fragment (moments + solve; solve alone from the moments):\n\n| method | cells "
      "| ns per fragment "
      "| ns solve |\n|---|---:|---:|---:|\n";
  for (const auto& r : timing) {
    md += "| " + r.method + " | " + std::to_string(r.cells) + " | " +
          fmt("%.0f", r.ns_per_fragment) + " | " + fmt("%.0f", r.ns_solve) + " |\n";
  }
  md +=
      "\nOne pass over the whole lens (every fragment matched and pulled):\n\n| level | cells | "
      "fragments | threads | "
      "ms | ns per cell | paths fast / exact / continuous / kept "
      "|\n|---:|---:|---:|---:|---:|---:|---|\n";
  for (const auto& r : lens) {
    md += "| " + std::to_string(r.level) + " | " + std::to_string(r.cells) + " | " +
          std::to_string(r.fragments) + " | " + std::to_string(r.threads) + " | " +
          fmt("%.3f", r.ms) + " | " + fmt("%.1f", r.ns_per_cell) + " | " + std::to_string(r.fast) +
          " / " + std::to_string(r.exact) + " / " + std::to_string(r.continuous) + " / " +
          std::to_string(r.kept) + " |\n";
  }
  md += "\n![shape matching cost](results/lens_shape_timing.png)\n\n";
  return md;
}

std::string sph_section(const std::vector<SphRow>& rows, const std::filesystem::path& dir) {
  Table t;
  t.columns = {"particles", "order",           "threads",    "subcells",        "build_ms",
               "pass_ms",   "mean_neighbours", "candidates", "ns_per_candidate"};
  for (const auto& r : rows)
    t.add({double(r.particles), std::string(sph::to_string(r.order)), double(r.threads),
           r.subcells ? 1.0 : 0.0, r.build_ms, r.pass_ms, r.mean_neighbours, r.candidates,
           r.ns_per_candidate});
  write_csv(t, dir / "lens_sph.csv");
  write_json(t, dir / "lens_sph.json");
  Chart c{.title = "SPH neighbour pass (about 28 neighbours each), one thread",
          .x = {"particles", Scale::Log10},
          .y = {"ms per pass", Scale::Log10}};
  std::map<std::string, Series> by;
  for (const auto& r : rows) {
    if (r.threads != 1) continue;
    const std::string key =
        std::string(sph::to_string(r.order)) +
        (r.order == sph::CellOrder::UnsortedHash ? ""
                                                 : (r.subcells ? ", sub-cells" : ", 2x2x2 block"));
    auto& s = by[key];
    s.name = key, s.fit_power_law = true;
    s.x.push_back(r.particles), s.y.push_back(r.pass_ms);
  }
  for (auto& [k, s] : by) c.series.push_back(s);
  c.markers = {{"target 10 ms", 100000, 10}};
  save_chart(c, dir / "lens_sph.png");
  std::string md =
      "### Fragment contact: SPH neighbour search on an ordered grid (seed 002 §6.1)\n\n"
      "`perf/lens/sph_measure`: N points uniform in a cube in random input order, density for 28 "
      "neighbours within h, grid cells 2h; the build (keys, sort, cell table) and one neighbour "
      "pass "
      "(poly6 density). Orders: Morton (the seed's), linear (x-runs scanned as one), and an "
      "unsorted "
      "spatial hash (the baseline). The default order is `" +
      std::string(sph::to_string(sph::default_order())) +
      "` (systems/sph/grid.hpp), chosen from this table.\n\n"
      "| particles | order | threads | sub-cells | build (ms) | pass (ms) | neighbours | "
      "candidates | ns "
      "per candidate |\n|---:|---|---:|:-:|---:|---:|---:|---:|---:|\n";
  for (const auto& r : rows) {
    md += "| " + std::to_string(r.particles) + " | " + sph::to_string(r.order) + " | " +
          std::to_string(r.threads) + " | " + yes_no(r.subcells) + " | " + fmt("%.2f", r.build_ms) +
          " | " + fmt("%.2f", r.pass_ms) + " | " + fmt("%.1f", r.mean_neighbours) + " | " +
          fmt("%.1f", r.candidates) + " | " + fmt("%.2f", r.ns_per_candidate) + " |\n";
  }
  md += "\n![sph](results/lens_sph.png)\n\n";
  return md;
}

std::string tools_section(const std::vector<LensToolsRow>& rows,
                          const std::vector<FragmentLensRow>& frag,
                          const std::filesystem::path& dir) {
  Table t;
  t.columns = {"level",  "cells",        "fragments",         "threads",
               "frames", "ms_per_frame", "contact_particles", "contact_pairs"};
  for (const auto& r : frag)
    t.add({double(r.level), double(r.cells), double(r.fragments), double(r.threads),
           double(r.frames), r.ms_per_frame, r.contact_particles, r.contact_pairs});
  write_csv(t, dir / "lens_fragments.csv");
  write_json(t, dir / "lens_fragments.json");
  std::string md =
      "### Tools on the lens and the fragmenting lens per frame\n\n"
      "`perf/lens/lens_tools_measure`: phaco erosion (roulette in the cone), aspirator, hook, "
      "Euler step "
      "and environment constraints, on n cells in the lens, per frame.\n\n"
      "| cells | threads | ms/frame | erosion | aspirate | hook | integrate | constrain | "
      "removed/frame "
      "|\n|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n";
  for (const auto& r : rows) {
    md += "| " + std::to_string(r.cells) + " | " + std::to_string(r.threads) + " | " +
          fmt("%.3f", r.ms_per_frame) + " | " + fmt("%.3f", r.erosion_ms) + " | " +
          fmt("%.3f", r.aspirate_ms) + " | " + fmt("%.3f", r.hook_ms) + " | " +
          fmt("%.3f", r.integrate_ms) + " | " + fmt("%.3f", r.constrain_ms) + " | " +
          fmt("%.1f", r.removed_per_frame) + " |\n";
  }
  md +=
      "\n`perf/lens/fragment_lens_measure` (procedures/lens/fragment_lens, the seed-002 pipeline): "
      "the lens cut by "
      "slabs into pieces, then stepped with no tool: gravity and viscosity, SPH contact between "
      "boundary cells of "
      "different fragments, constraints, shape matching of every fragment. Target: 50k cells in "
      "fragments, ≤ 3 ms "
      "per frame on 2 threads.\n\n| level | cells | fragments | threads | ms/frame | contact "
      "particles | contact "
      "pairs |\n|---:|---:|---:|---:|---:|---:|---:|\n";
  for (const auto& r : frag) {
    md += "| " + std::to_string(r.level) + " | " + std::to_string(r.cells) + " | " +
          std::to_string(r.fragments) + " | " + std::to_string(r.threads) + " | " +
          fmt("%.3f", r.ms_per_frame) + " | " + fmt("%.0f", r.contact_particles) + " | " +
          fmt("%.0f", r.contact_pairs) + " |\n";
  }
  return md + "\n";
}

std::string scene_section(const std::vector<LensSceneRow>& rows, const std::filesystem::path& dir) {
  Table t;
  t.columns = {"level",
               "tets",
               "frames",
               "frame_p50_ms",
               "frame_p99_ms",
               "lens_sculpt_p50_ms",
               "lens_sculpt_p99_ms",
               "sculpt_step_mean_ms",
               "sculpt_step_max_ms",
               "tets_removed",
               "volume_removed_mm3",
               "nucleus_rotation_deg",
               "trenches",
               "trench1_width_mm",
               "trench2_width_mm",
               "trench1_depth_fraction",
               "trench2_depth_fraction",
               "crossing_angle_deg"};
  for (const auto& r : rows)
    t.add({double(r.level), r.tets, r.frames, r.frame_p50_ms, r.frame_p99_ms, r.sculpt_p50_ms,
           r.sculpt_p99_ms, r.step_mean_ms, r.step_max_ms, r.removed, r.volume_mm3, r.rotation_deg,
           r.trenches, r.width0, r.width1, r.depth0, r.depth1, r.crossing_deg});
  write_csv(t, dir / "lens_scene.csv");
  write_json(t, dir / "lens_scene.json");
  std::string md =
      "### In the scene: the divide-and-conquer demo per level\n\n"
      "`phaco run data/scenarios/phaco_sculpting_demo.json` with the eye level changed, one "
      "thread: two "
      "trenches of four passes in two lanes each, a quarter turn of the nucleus between them (seed "
      "000 "
      "§5.4 push), the trench measures from the removed tets (procedures/lens/trench_measure). "
      "Targets "
      "(DESIGN.md §6): width 1.4-2.0 mm, depth about 80 % of the nucleus, crossing 90°.\n\n"
      "| level | tets | frame p50 / p99 (ms) | lens_sculpt p50 / p99 (ms) | sculpt step mean / max "
      "(ms) | "
      "tets removed | removed (mm3) | nucleus turned (deg) | trench widths (mm) | depths (% "
      "nucleus) | "
      "crossing (deg) |\n|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n";
  for (const auto& r : rows) {
    md += "| " + std::to_string(r.level) + " | " + fmt("%.0f", r.tets) + " | " +
          fmt("%.3f", r.frame_p50_ms) + " / " + fmt("%.3f", r.frame_p99_ms) + " | " +
          fmt("%.3f", r.sculpt_p50_ms) + " / " + fmt("%.3f", r.sculpt_p99_ms) + " | " +
          fmt("%.3f", r.step_mean_ms) + " / " + fmt("%.2f", r.step_max_ms) + " | " +
          fmt("%.0f", r.removed) + " | " + fmt("%.2f", r.volume_mm3) + " | " +
          fmt("%.1f", r.rotation_deg) + " | " + fmt("%.2f", r.width0) + ", " +
          fmt("%.2f", r.width1) + " | " + fmt("%.0f", 100 * r.depth0) + ", " +
          fmt("%.0f", 100 * r.depth1) + " | " + fmt("%.1f", r.crossing_deg) + " |\n";
  }
  return md + "\n";
}

}  // namespace

void run_lens(const StudyOptions& options) {
  bool million = !options.quick;
  for (const auto& e : options.extra) {
    if (e == "--no-million")
      million = false;
    else
      throw InputError("lens: unknown option '" + e + "'");
  }
  const std::string load = load_note();
  const auto dir = options.out_dir / "results";
  Progress progress(8);

  progress.step("lens: sculpting");
  SculptMeasureOptions so;
  so.levels = options.quick ? std::vector<int>{0, 1} : std::vector<int>{0, 1, 2, 3, 5, 7};
  const auto sculpt_rows = measure_sculpt(so);

  progress.step("lens: simplex cells");
  SimplexMeasureOptions xo;
  xo.levels = options.quick ? std::vector<int>{0, 1} : std::vector<int>{0, 1, 2, 3, 5};
  if (options.quick) xo.min_seconds = 0.02, xo.repeats = 1;
  const auto simplex_rows = measure_simplex(xo);

  progress.step("lens: shape matching");
  const auto deg = measure_shape_degenerate(options.quick ? 40 : 200);
  const auto prec = measure_shape_precision(options.quick ? 40 : 200);
  const auto timing = measure_shape_timing(options.quick ? 0.01 : 0.05);
  const auto lens_pass =
      measure_shape_lens(options.quick ? 1 : 3, {1, 100, 5000}, {1, 2}, options.quick ? 0.02 : 0.2);

  progress.step("lens: SPH neighbour search");
  SphMeasureOptions sp = sph_default_options(million);
  if (options.quick) sp.sizes = {10'000}, sp.min_seconds = 0.02, sp.repeats = 1;
  const auto sph_rows = measure_sph(sp);

  progress.step("lens: tools");
  const std::vector<uint32_t> cells = options.quick
                                          ? std::vector<uint32_t>{10'000}
                                          : std::vector<uint32_t>{10'000, 50'000, 200'000};
  const std::vector<int> threads = {1, 2};
  const auto tool_rows =
      measure_lens_tools(cells, threads, options.quick ? 20 : 120, 5, options.quick ? 1 : 3);

  progress.step("lens: fragmenting lens");
  const std::vector<int> frag_levels = {options.quick ? 1 : 3};
  const std::vector<int> cuts = {0, 1, 3};
  const auto frag_rows = measure_fragment_lens(frag_levels, cuts, threads, options.quick ? 10 : 60,
                                               options.quick ? 1 : 3);

  progress.step("lens: demo scene");
  std::vector<LensSceneRow> scene_rows;
  for (int level : options.quick ? std::vector<int>{0, 1} : std::vector<int>{0, 1, 2, 3, 5}) {
    scene_rows.push_back(measure_scene(level));
  }
  progress.step("lens: writing");

  std::string md = "## The lens: sculpting, simplex cells, shape matching, SPH (issue 5)\n\n";
  md += std::string("Measured by `phaco-perf lens") + (options.quick ? " --quick" : "") + "`, " +
        load + ".\n\n";
  md += sculpt_section(sculpt_rows, dir);
  md += simplex_section(simplex_rows, dir);
  md += shape_section(deg, prec, timing, lens_pass, dir);
  md += sph_section(sph_rows, dir);
  md += tools_section(tool_rows, frag_rows, dir);
  md += scene_section(scene_rows, dir);
  write_section(dir, "lens", md);
  progress.finish();
}

}  // namespace phaco::perf
