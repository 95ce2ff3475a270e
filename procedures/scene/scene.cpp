#include "procedures/scene/scene.hpp"

#include <algorithm>

#include "components/from_mesh.hpp"
#include "components/held_fragment.hpp"
#include "components/particles.hpp"
#include "components/tets.hpp"
#include "components/tool.hpp"
#include "components/triangles.hpp"
#include "engine/core/clock.hpp"
#include "engine/core/error.hpp"
#include "engine/core/state_hash.hpp"
#include "engine/io/json_reader.hpp"
#include "engine/io/mesh_obj.hpp"
#include "procedures/eye/difficulty.hpp"
#include "procedures/eye/eye_geometry.hpp"
#include "procedures/eye/eye_mesh.hpp"
#include "procedures/eye/mesh_cache.hpp"
#include "procedures/scene/capsule_cutting.hpp"
#include "procedures/scene/capsule_physics.hpp"
#include "procedures/scene/cornea_cutting.hpp"
#include "procedures/scene/density_units.hpp"
#include "procedures/scene/drill_metrics.hpp"
#include "procedures/scene/haptic_publish.hpp"
#include "procedures/scene/lens_fragments.hpp"
#include "procedures/scene/lens_sculpting.hpp"
#include "procedures/scene/method_settings.hpp"
#include "procedures/scene/scene_inputs.hpp"
#include "procedures/scene/tool_ports.hpp"
#include "procedures/scene/track_pivot.hpp"
#include "systems/tool_motion/tool_motion.hpp"

namespace phaco {

namespace {

std::vector<std::string> to_strings(std::span<const char* const> names) {
  return {names.begin(), names.end()};
}

// Eye file, then the drill's difficulty, then the scenario's explicit overrides (they win).
eye::EyeParams load_params(const Scenario& s, const DifficultySettings& difficulty) {
  eye::EyeParams params =
      s.eye.params_file ? eye::load_eye_params(*s.eye.params_file) : eye::default_eye_params();
  try {
    eye::apply_difficulty(params, difficulty);
  } catch (const InputError& e) {
    throw InputError(s.source + ": difficulty: " + e.what());
  }
  for (const auto& [key, value] : s.eye.overrides) {
    try {
      eye::apply_override(params, key, value);
    } catch (const InputError& e) {
      throw InputError(s.source + ": " + io::path_key("eye.overrides", key) + ": " + e.what());
    }
  }
  // Each value in its range can still make an impossible eye (a capsule wider than the lens):
  // caught here, before any mesh, so `phaco validate` sees it too.
  try {
    eye::eye_geometry(params);
  } catch (const InputError& e) {
    throw InputError(s.source + ": eye: " + e.what());
  }
  return params;
}

const SurfaceMesh& surface_of(const eye::EyeMeshes& m, BodyPart part) {
  switch (part) {
    case BodyPart::Cornea:
      return m.cornea;
    case BodyPart::Capsule:
      return m.capsule;
    case BodyPart::Iris:
      return m.iris;
    case BodyPart::Globe:
      return m.globe;
    default:
      return m.lens_surface;
  }
}

// Lumped mass of a membrane: each triangle gives a third of ρ·h·A to each corner.
std::vector<double> membrane_masses(const SurfaceMesh& mesh, double density_kg_m3,
                                    double thickness_mm) {
  std::vector<double> mass(mesh.vertices.size(), 0.0);
  for (const auto& t : mesh.triangles) {
    const Vec3& a = mesh.vertices[t[0]];
    const double area = 0.5 * (mesh.vertices[t[1]] - a).cross(mesh.vertices[t[2]] - a).norm();
    const double m = density_kg_m3 * kKgPerMm3PerKgPerM3 * thickness_mm * area / 3.0;
    for (uint32_t v : t) mass[v] += m;
  }
  return mass;
}

// Vertices on an open membrane's rim: the capsule is held there by the zonules.
std::vector<uint8_t> rim_vertices(const SurfaceMesh& mesh) {
  std::vector<std::pair<uint64_t, int>> edges;
  edges.reserve(mesh.triangles.size() * 3);
  for (const auto& t : mesh.triangles) {
    for (int k = 0; k < 3; ++k) {
      const uint32_t a = t[k], b = t[(k + 1) % 3];
      edges.push_back({(uint64_t{std::min(a, b)} << 32) | std::max(a, b), 1});
    }
  }
  std::sort(edges.begin(), edges.end());
  std::vector<uint8_t> rim(mesh.vertices.size(), 0);
  for (size_t i = 0; i < edges.size();) {
    size_t j = i;
    while (j < edges.size() && edges[j].first == edges[i].first) ++j;
    if (j - i == 1) {
      rim[edges[i].first >> 32] = 1;
      rim[edges[i].first & 0xFFFFFFFFu] = 1;
    }
    i = j;
  }
  return rim;
}

Tets make_tets(const TetMesh& mesh) {
  Tets t;
  table_append(t, static_cast<uint32_t>(mesh.tets.size()));
  for (size_t i = 0; i < mesh.tets.size(); ++i) {
    t.a[i] = mesh.tets[i][0];
    t.b[i] = mesh.tets[i][1];
    t.c[i] = mesh.tets[i][2];
    t.d[i] = mesh.tets[i][3];
    t.region[i] = i < mesh.region.size() ? mesh.region[i] : 0;
  }
  return t;
}

// A membrane an earlier step of the procedure left (carried_state.hpp), as it stood.
void add_carried_surface(Scene& scene, Entity e, const CarriedSurface& s) {
  Particles particles = particles_at(s.vertices, ParticleKind::Anchored, 0.0f);
  particles.kind = s.kind;
  particles.inv_mass = s.inv_mass;
  SurfaceMesh mesh;
  mesh.triangles = s.triangles;
  scene.world.add(e, std::move(particles));
  scene.world.add(e, triangles_of(mesh));
}

const CarriedSurface* carried_surface(const Scene& scene, BodyPart part) {
  if (part == BodyPart::Cornea && scene.carried.cornea) return &*scene.carried.cornea;
  if (part == BodyPart::Capsule && scene.carried.capsule) return &*scene.carried.capsule;
  return nullptr;
}

void add_body(Scene& scene, BodyPart part, const eye::EyeMeshes& meshes) {
  const Entity e = scene.world.create(EntityKind::Body, std::string(to_string(part)));
  scene.world.add(e, Body{part});
  if (const CarriedSurface* carried = carried_surface(scene, part)) {
    add_carried_surface(scene, e, *carried);
  } else if (part == BodyPart::Lens) {
    scene.world.add(e, particles_at(meshes.lens_tets->vertices, ParticleKind::Anchored, 0.0f));
    scene.world.add(e, make_tets(*meshes.lens_tets));
  } else {
    const SurfaceMesh& mesh = surface_of(meshes, part);
    Particles particles =
        particles_at(mesh.vertices, ParticleKind::Anchored, 0.0f);  // rigid until a system frees it
    if (part == BodyPart::Capsule) {
      const auto mass = membrane_masses(mesh, scene.params.get("capsule.density_kg_m3"),
                                        scene.params.get("capsule.thickness_mm"));
      const auto rim = rim_vertices(mesh);
      for (size_t i = 0; i < mass.size(); ++i) {
        particles.kind[i] = rim[i] ? ParticleKind::Anchored : ParticleKind::Free;
        particles.inv_mass[i] = rim[i] || mass[i] <= 0 ? 0.0f : static_cast<float>(1.0 / mass[i]);
      }
    }
    scene.world.add(e, std::move(particles));
    scene.world.add(e, triangles_of(mesh));
  }
  scene.bodies.push_back(e);
}

void replace_meshes_from_files(const Scenario& s, eye::EyeMeshes& meshes) {
  for (const auto& [name, path] : s.eye.meshes) {
    SurfaceMesh* target = name == "cornea"         ? &meshes.cornea
                          : name == "capsule"      ? &meshes.capsule
                          : name == "iris"         ? &meshes.iris
                          : name == "globe"        ? &meshes.globe
                          : name == "lens_surface" ? &meshes.lens_surface
                                                   : nullptr;
    if (!target) throw InputError(s.source + ": eye.meshes." + name + ": unknown body");
    try {
      *target = read_obj(path);
    } catch (const InputError& e) {
      throw InputError(s.source + ": eye.meshes." + name + ": " + e.what());
    }
  }
}

BodyPart body_part(std::string_view name) {
  for (BodyPart p : {BodyPart::Cornea, BodyPart::Capsule, BodyPart::Iris, BodyPart::Globe,
                     BodyPart::LensSurface, BodyPart::Lens}) {
    if (to_string(p) == name) return p;
  }
  throw InputError("unknown body '" + std::string(name) + "'");  // drill files are checked on load
}

// Each hand's tool must be one the drill gives that hand.
void check_tools(const Scenario& s, const DrillFile& d) {
  for (const HandTrack& h : s.hands) {
    const auto& allowed = h.hand == Hand::Left ? d.left_tools : d.right_tools;
    if (std::find(allowed.begin(), allowed.end(), h.tool) != allowed.end()) continue;
    std::string names;
    for (ToolKind t : allowed) names += (names.empty() ? "" : ", ") + std::string(to_string(t));
    throw InputError(s.source + ": hands." + std::string(to_string(h.hand)) + ".tool: the " +
                     std::string(to_string(s.drill)) + " drill (" + d.source + ") gives the " +
                     std::string(to_string(h.hand)) + " hand " +
                     (names.empty() ? std::string("no tool") : names) + "; got " +
                     std::string(to_string(h.tool)));
  }
}

bool is_lens_method(const std::string& key) {
  return key == "lens.model" || key == "lens.broadphase" || key == "lens.narrowphase";
}

// Every `methods` key must name a setting of a body this drill's scene has.
void check_methods(const Scenario& s, const std::vector<BodyPart>& parts) {
  auto has = [&](BodyPart part) {
    return std::find(parts.begin(), parts.end(), part) != parts.end();
  };
  for (const auto& [key, value] : s.methods) {
    const bool capsule = is_capsule_method(key), lens = is_lens_method(key);
    if (is_ports_method(key)) continue;  // any drill; the value is checked by ports_mode
    if (!capsule && !lens) {
      throw InputError(
          s.source + ": methods[\"" + key +
          "\"]: unknown method setting; expected one of: capsule.integrator, capsule.spring_law, "
          "capsule.stiffness, capsule.pretension, capsule.active_set, capsule.cutting, "
          "capsule.tear_rule, capsule.preconditioner, capsule.cg_tolerance, lens.model, "
          "lens.broadphase, lens.narrowphase, tools.ports");
    }
    if (capsule && !has(BodyPart::Capsule)) {
      throw InputError(s.source + ": methods[\"" + key + "\"]: the " +
                       std::string(to_string(s.drill)) + " scene has no capsule");
    }
    if (lens && !has(BodyPart::Lens)) {
      throw InputError(s.source + ": methods[\"" + key + "\"]: the " +
                       std::string(to_string(s.drill)) + " scene has no tetrahedral lens");
    }
  }
}

// Access names of the components every scene has (the check of declared access, SystemDesc);
// each add_* function names the components it adds.
void name_base_components(World& world) {
  world.name_component<Body>("body", AccessKind::Constant);
  world.name_component<Particles>("particles");
  world.name_component<Triangles>("triangles");
  world.name_component<Tets>("tets");
  world.name_component<Tool>("kind", AccessKind::Constant);
  world.name_component<ToolTrack>("track");
  world.name_component<ToolState>("pose");
  world.name_component<HeldFragment>("held");  // filled by the drill's aspiration
}

std::vector<SystemDesc> base_systems(Scene& scene) {
  std::vector<SystemDesc> systems;
  systems.push_back({.name = "move_tools",
                     .phase = Phase::Input,
                     .reads = to_strings(tool_motion::kReads),
                     .writes = to_strings(tool_motion::kWrites),
                     .run = [&scene](const FrameContext& ctx) {
                       const double t_end = ctx.time_s + ctx.dt_s;
                       for (Entity e : scene.tools) {
                         ToolState& pose = scene.world.at<ToolState>(e);
                         const ToolTrack& track = scene.world.at<ToolTrack>(e);
                         const Hand hand = scene.world.at<Tool>(e).hand;
                         // A device replaces the track of its hand (DESIGN.md §7). Until its
                         // first pose arrives the tool waits at the track's start, where the
                         // device starts too, rather than following the script for a few
                         // frames and jumping back (issue 24: 0.07 mm on an untouched hand).
                         const auto& pivot = scene.track_pivots[static_cast<size_t>(hand) & 1u];
                         if (scene.haptics && scene.haptics->drives(hand)) {
                           if (!scene.haptics->newest_pose(hand, pose))
                             tool_motion::move_tool(track, pose, 0.0);
                           pivot_track_pose(pose, pivot);
                           continue;
                         }
                         tool_motion::move_tool(track, pose, t_end);
                         pivot_track_pose(pose, pivot);
                       }
                     }});
  // The frame's one sync point for structural change (DESIGN.md §4, step 3).
  systems.push_back({.name = "apply_commands",
                     .phase = Phase::Topology,
                     .writes = {"world.structure"},
                     .barrier = true,
                     .run = [&scene](const FrameContext&) { scene.commands.apply(scene.world); }});
  return systems;
}

}  // namespace

DrillFile load_drill_for(const Scenario& s) {
  const std::filesystem::path file =
      s.drill_file ? *s.drill_file  // checked to exist when the scenario was read
                   : eye::data_dir() / "drills" / (std::string(to_string(s.drill)) + ".json");
  if (!std::filesystem::exists(file)) {
    throw InputError(s.source + ": drill: no drill file for '" + std::string(to_string(s.drill)) +
                     "' at " + file.string() + " (give \"drill_file\" or set PHACO_DATA_DIR)");
  }
  DrillFile d = load_drill_file(file);
  if (d.drill != s.drill) {
    throw InputError(s.source + ": drill_file: " + d.source + " is a '" +
                     std::string(to_string(d.drill)) + "' drill; the scenario is '" +
                     std::string(to_string(s.drill)) + "'");
  }
  return d;
}

nlohmann::json drill_setup_json(const Scene& scene) {
  const DifficultySettings& d = scene.difficulty;
  nlohmann::json settings = nlohmann::json::object();
  if (d.patient_age_years) settings["patient_age_years"] = *d.patient_age_years;
  if (d.anterior_bowing_kpa) settings["anterior_bowing_kpa"] = *d.anterior_bowing_kpa;
  if (d.anterior_chamber_depth_mm)
    settings["anterior_chamber_depth_mm"] = *d.anterior_chamber_depth_mm;
  if (d.nucleus_hardness) settings["nucleus_hardness"] = *d.nucleus_hardness;
  return {{"file", scene.drill.source},
          {"title", scene.drill.title},
          {"difficulty", scene.scenario.difficulty.empty() ? scene.drill.default_difficulty
                                                           : scene.scenario.difficulty},
          {"settings", std::move(settings)}};
}

std::optional<Entity> Scene::body(BodyPart part) const {
  for (Entity e : bodies) {
    if (const Body* b = world.get<Body>(e); b && b->part == part) return e;
  }
  return std::nullopt;
}

SceneInputs check_scene_inputs(const Scenario& scenario) {
  SceneInputs in;
  in.drill = load_drill_for(scenario);
  check_tools(scenario, in.drill);
  in.difficulty = resolve_difficulty(in.drill, scenario.difficulty, scenario.difficulty_settings,
                                     scenario.source);
  in.params = load_params(scenario, in.difficulty);
  std::vector<BodyPart> parts;
  for (const std::string& name : in.drill.bodies) parts.push_back(body_part(name));
  check_methods(scenario, parts);
  check_method_values(scenario, in.drill);
  return in;
}

std::unique_ptr<Scene> build_scene(const Scenario& scenario, const SceneOptions& options) {
  auto scene = std::make_unique<Scene>();
  scene->scenario = scenario;
  SceneInputs inputs = check_scene_inputs(scenario);
  scene->drill = std::move(inputs.drill);
  scene->difficulty = inputs.difficulty;
  scene->params = std::move(inputs.params);
  scene->resolution = eye::resolution_for_level(scenario.eye.level);
  scene->commands = CommandQueues(options.threads);
  scene->haptics = options.haptics;
  if (options.carried) scene->carried = *options.carried;

  std::vector<BodyPart> parts;
  for (const std::string& name : scene->drill.bodies) parts.push_back(body_part(name));
  const bool need_tets = std::find(parts.begin(), parts.end(), BodyPart::Lens) != parts.end();
  const auto layout = scenario.eye.capsule_layout == "isotropic" ? eye::CapsuleLayout::Isotropic
                                                                 : eye::CapsuleLayout::Curvilinear;
  Stopwatch mesh_clock;
  eye::MeshCache cache(options.cache_dir.value_or(eye::MeshCache::default_dir()));
  eye::EyeMeshes meshes = cache.load_or_build(scene->params, scene->resolution, layout, need_tets);
  replace_meshes_from_files(scenario, meshes);
  scene->mesh_load_s = mesh_clock.elapsed_s();

  name_base_components(scene->world);
  for (BodyPart part : parts) add_body(*scene, part, meshes);
  scene->track_pivots = track_pivots(*scene);
  for (const HandTrack& hand : scenario.hands) {
    const Entity e = scene->world.create(EntityKind::Tool, std::string(to_string(hand.hand)) + "." +
                                                               std::string(to_string(hand.tool)));
    scene->world.add(e, Tool{hand.tool, hand.hand});
    scene->world.add(e, ToolTrack{hand.track});
    ToolState start = sample_track(hand.track, 0.0);
    pivot_track_pose(start, scene->track_pivots[static_cast<size_t>(hand.hand) & 1u]);
    scene->world.add(e, start);
    scene->tools.push_back(e);
  }

  std::vector<SystemDesc> systems = base_systems(*scene);
  // Tools in the corneal ports turning the globe (issue 7 item 2); none when "tools.ports" is off.
  if (auto ports = tool_ports_system(*scene)) systems.push_back(std::move(*ports));
  if (scene->body(BodyPart::Capsule)) {
    add_capsule_physics(*scene);
    systems.push_back(capsule_dynamics_system(*scene));
    if (add_capsule_cutting(*scene)) systems.push_back(capsule_cut_system(*scene));
  }
  if (scene->body(BodyPart::Lens)) {
    if (lens_model(*scene) == "fragments") {
      add_lens_fragments(*scene);
      systems.push_back(lens_fragments_system(*scene));
    } else {
      add_lens_sculpting(*scene);
      systems.push_back(lens_sculpt_system(*scene));
    }
  }
  // The keratome cuts the cornea (issue 7, corneal incision).
  if (add_cornea_cutting(*scene)) systems.push_back(cornea_cut_system(*scene));
  if (scene->haptics) systems.push_back(haptic_publish_system(*scene));
  systems.push_back(drill_metrics_system(*scene));  // last: it only reads (issue 7 item 3)
  if (options.extra_systems) {
    for (auto& s : options.extra_systems(*scene)) systems.push_back(std::move(s));
  }
  // apply_commands is the frame's sync point for structural change only where a system records
  // commands (declares writes "world.commands"). Where none does it has nothing to apply, and as
  // a barrier it would only keep the port solve, the capsule and the metrics from overlapping.
  const bool records = std::any_of(systems.begin(), systems.end(), [](const SystemDesc& s) {
    return std::find(s.writes.begin(), s.writes.end(), "world.commands") != s.writes.end();
  });
  for (SystemDesc& s : systems)
    if (s.name == "apply_commands") s.barrier = records, s.reads = {"world.commands"};
  scene->graph = std::make_unique<FrameGraph>(std::move(systems));
  scene->executor = std::make_unique<Executor>(
      *scene->graph, options.threads,
      ExecutorSettings{.access_check = options.access_check, .dispatch = options.dispatch});
  return scene;
}

void step(Scene& scene) {
  const FrameContext ctx{scene.frame, scene.time_s, scene.scenario.dt_s};
  scene.executor->run_frame(ctx);
  ++scene.frame;
  // Time from the frame count, not by accumulation, so it does not drift over long runs.
  scene.time_s = static_cast<double>(scene.frame) * scene.scenario.dt_s;
}

std::string state_hash(const Scene& scene) {
  StateHash h;
  auto& world = const_cast<World&>(scene.world);  // read-only walk; each() is non-const
  for (Entity e : scene.bodies) {
    h.add_string(world.name(e));
    if (const Particles* p = world.get<Particles>(e)) {
      h.add(p->slots.alive_mask());
      for (const auto* col : {&p->x, &p->y, &p->z, &p->vx, &p->vy, &p->vz, &p->inv_mass}) {
        h.add(std::span<const float>(*col));
      }
    }
    if (const Triangles* t = world.get<Triangles>(e)) {
      h.add(t->slots.alive_mask());
      for (const auto* col : {&t->a, &t->b, &t->c}) h.add(std::span<const uint32_t>(*col));
    }
    if (const Tets* t = world.get<Tets>(e)) {
      h.add(t->slots.alive_mask());
      for (const auto* col : {&t->a, &t->b, &t->c, &t->d}) h.add(std::span<const uint32_t>(*col));
    }
    if (const LensFragments* lf = world.get<LensFragments>(e)) {
      const SimplexCells& c = lf->lens.cells;
      for (const auto* col : {&c.x, &c.y, &c.z}) h.add(std::span<const float>(*col));
    }
  }
  for (Entity e : scene.tools) {
    const ToolState& s = world.at<ToolState>(e);
    const double v[] = {s.pos.x(),  s.pos.y(),  s.pos.z(), s.quat.w(), s.quat.x(),
                        s.quat.y(), s.quat.z(), s.grip,    s.pedal};
    h.add(std::span<const double>(v));
  }
  return h.hex();
}

std::vector<std::pair<std::string, uint64_t>> element_counts(const Scene& scene) {
  std::vector<std::pair<std::string, uint64_t>> out;
  for (Entity e : scene.bodies) {
    const std::string& name = scene.world.name(e);
    if (const auto* p = scene.world.get<Particles>(e))
      out.push_back({name + ".particles", p->slots.live_count()});
    if (const auto* t = scene.world.get<Triangles>(e))
      out.push_back({name + ".triangles", t->slots.live_count()});
    if (const auto* t = scene.world.get<Tets>(e))
      out.push_back({name + ".tets", t->slots.live_count()});
  }
  out.push_back({"tools", scene.tools.size()});
  return out;
}

}  // namespace phaco
