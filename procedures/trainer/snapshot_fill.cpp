#include "procedures/trainer/snapshot_fill.hpp"

#include <algorithm>
#include <array>
#include <atomic>
#include <optional>
#include <vector>

#include "components/body.hpp"
#include "components/particles.hpp"
#include "components/tool.hpp"
#include "components/triangles.hpp"
#include "engine/core/error.hpp"
#include "procedures/scene/capsule_physics.hpp"
#include "procedures/scene/lens_fragments.hpp"
#include "procedures/scene/lens_sculpting.hpp"
#include "procedures/scene/scene.hpp"
#include "procedures/scene/tool_ports.hpp"
#include "procedures/trainer/tip_height.hpp"
#include "systems/simplex/simplex_surface.hpp"

namespace phaco {

namespace {

using render::BodyView;
using render::Look;

constexpr uint32_t kUnmapped = 0xFFFFFFFFu;

// Topology versions for every view of every scene in the process: never repeated.
std::atomic<uint64_t> g_topology_version{0};

struct ViewCache {
  uint64_t hash = 0;
  uint64_t version = 0;
  bool filled = false;
  std::vector<uint32_t> edges;  // the capsule's open edges, recomputed on topology change
};

// The filler's memory between fills, kept on the scene's first body.
struct SnapshotFillCache {
  std::vector<ViewCache> views;
  std::vector<uint32_t> remap;                    // old vertex index → compact, kUnmapped
  std::vector<uint32_t> touched;                  // remap entries to reset
  std::vector<uint64_t> edge_keys;                // scratch for open edges
  std::vector<std::array<uint32_t, 3>> faces;     // scratch: global-index triangles
  std::vector<std::array<uint32_t, 3>> interior;  // scratch: newly exposed faces
  simplex::BoundarySurface boundary;              // fragments lens
  // The tet lens's two views as last compacted (their triangles and, per view vertex, its
  // particle): sculpting only removes tets, so while alive_count stands still the faces do too
  // and a fill re-gathers positions only, instead of walking every surface tet (120 times a
  // second: the largest part of this function's cost in the sculpting drill).
  const TetTopology* lens_topology = nullptr;
  uint32_t lens_alive = 0;
  size_t lens_particles = 0;
  std::array<std::vector<uint32_t>, 2> lens_tris, lens_nodes;  // outer, inner
  std::vector<uint8_t> face_was_external;  // fragments lens, per face id, at first fill
  std::vector<Vec3> ports;                 // guidance ports when no ports record
  bool ports_made = false;
  float reflex_attenuation = -1;        // lens, 1/mm; set at the first fill
  std::optional<eye::EyeGeometry> eye;  // the depth cue's layout; set at the first fill
  bool has_capsule = false;
};

// How much each mm of the sculptable lens dims the red reflex (render::BodyView): a harder, browner
// nucleus dims it more. At the standard hardness 0.5 the intact lens (4.5 mm on the axis) passes
// exp(−0.4 × 4.5) ≈ 17 % of the reflex and a trench floor 1.5 mm above the posterior pole ≈ 55 %:
// the floor glows as the trench deepens (issue 19 item 4). The rhexis drill's lens_surface stays
// clear (0): there the reflex is what shows the capsule's flap.
float reflex_attenuation(const Scene& scene) {
  const auto it = scene.params.values.find("lens_model.nucleus_hardness");
  const double hardness = it == scene.params.values.end() ? 0.5 : it->second;
  return static_cast<float>(0.2 + 0.4 * std::clamp(hardness, 0.0, 1.0));
}

// FNV-1a over four interleaved lanes, then the lanes and the length: a quarter of the dependent
// multiplies of one lane (every fill hashes every body's indices, 120 times a second).
uint64_t fnv(uint64_t h, std::span<const uint32_t> v) {
  constexpr uint64_t kPrime = 0x100000001b3ull;
  uint64_t lane[4] = {h, h ^ 1, h ^ 2, h ^ 3};
  size_t i = 0;
  for (; i + 4 <= v.size(); i += 4)
    for (size_t k = 0; k < 4; ++k) lane[k] = (lane[k] ^ v[i + k]) * kPrime;
  for (; i < v.size(); ++i) lane[0] = (lane[0] ^ v[i]) * kPrime;
  for (uint64_t x : {lane[0], lane[1], lane[2], lane[3], uint64_t{v.size()}}) h = (h ^ x) * kPrime;
  return h;
}

Look look_of(BodyPart part) {
  switch (part) {
    case BodyPart::Globe:
      return Look::Sclera;
    case BodyPart::Iris:
      return Look::Iris;
    case BodyPart::Cornea:
      return Look::Cornea;
    case BodyPart::Capsule:
      return Look::Capsule;
    case BodyPart::LensSurface:
      return Look::LensSurface;
    case BodyPart::Lens:
      return Look::LensSurface;
  }
  return Look::Capsule;
}

// The view at `index`, created on the first fill of a snapshot.
BodyView& view_at(render::RenderSnapshot& snap, SnapshotFillCache& cache, size_t index,
                  std::string_view name, Look look) {
  if (snap.bodies.size() <= index) snap.bodies.resize(index + 1);
  if (cache.views.size() <= index) cache.views.resize(index + 1);
  BodyView& v = snap.bodies[index];
  if (v.name != name) v.name.assign(name.data(), name.size());
  v.look = look;
  return v;
}

// Bumps the view's version when its indices changed since the last fill; writes it and the
// cached edges into the view.
void finish_view(BodyView& v, ViewCache& c, bool with_edges, SnapshotFillCache& cache) {
  const uint64_t h = fnv(0xcbf29ce484222325ull, v.tris);
  if (!c.filled || h != c.hash) {
    c.hash = h;
    c.filled = true;
    c.version = g_topology_version.fetch_add(1, std::memory_order_relaxed) + 1;
    c.edges.clear();
    if (with_edges) {
      // Edges used by one live triangle only: sort the undirected edge keys, keep singletons.
      cache.edge_keys.clear();
      for (size_t t = 0; t + 2 < v.tris.size(); t += 3) {
        for (int k = 0; k < 3; ++k) {
          const uint32_t a = v.tris[t + k], b = v.tris[t + (k + 1) % 3];
          cache.edge_keys.push_back((uint64_t{std::min(a, b)} << 32) | std::max(a, b));
        }
      }
      std::sort(cache.edge_keys.begin(), cache.edge_keys.end());
      for (size_t i = 0; i < cache.edge_keys.size();) {
        size_t j = i;
        while (j < cache.edge_keys.size() && cache.edge_keys[j] == cache.edge_keys[i]) ++j;
        if (j - i == 1) {
          c.edges.push_back(static_cast<uint32_t>(cache.edge_keys[i] >> 32));
          c.edges.push_back(static_cast<uint32_t>(cache.edge_keys[i] & 0xFFFFFFFFu));
        }
        i = j;
      }
    }
  }
  v.edges.assign(c.edges.begin(), c.edges.end());
  v.topology_version = c.version;
}

// Compacts `faces` (indices into x/y/z) into the view: only referenced vertices, in first-use
// order.
void compact_faces(BodyView& v, std::span<const std::array<uint32_t, 3>> faces,
                   std::span<const float> x, std::span<const float> y, std::span<const float> z,
                   SnapshotFillCache& cache) {
  v.xyz.clear();
  v.tris.clear();
  if (cache.remap.size() < x.size()) cache.remap.resize(x.size(), kUnmapped);
  cache.touched.clear();
  for (const auto& f : faces) {
    if (f[0] >= x.size() || f[1] >= x.size() || f[2] >= x.size()) continue;
    for (uint32_t i : f) {
      uint32_t& m = cache.remap[i];
      if (m == kUnmapped) {
        m = static_cast<uint32_t>(v.xyz.size() / 3);
        v.xyz.push_back(x[i]), v.xyz.push_back(y[i]), v.xyz.push_back(z[i]);
        cache.touched.push_back(i);
      }
      v.tris.push_back(m);
    }
  }
  for (uint32_t i : cache.touched) cache.remap[i] = kUnmapped;
}

// A surface body: live particles (compacted) and live triangles.
void fill_surface(BodyView& v, const Particles& p, const Triangles& t, SnapshotFillCache& cache) {
  v.xyz.clear();
  v.tris.clear();
  const uint32_t n = p.slots.size();
  if (cache.remap.size() < n) cache.remap.resize(n, kUnmapped);
  for (uint32_t i = 0; i < n; ++i) {
    if (!p.slots.alive(i)) {
      cache.remap[i] = kUnmapped;
      continue;
    }
    cache.remap[i] = static_cast<uint32_t>(v.xyz.size() / 3);
    v.xyz.push_back(p.x[i]), v.xyz.push_back(p.y[i]), v.xyz.push_back(p.z[i]);
  }
  for (uint32_t k = 0; k < t.slots.size(); ++k) {
    if (!t.slots.alive(k)) continue;
    const uint32_t a = t.a[k], b = t.b[k], c = t.c[k];
    if (a >= n || b >= n || c >= n) continue;
    const uint32_t ra = cache.remap[a], rb = cache.remap[b], rc = cache.remap[c];
    if (ra == kUnmapped || rb == kUnmapped || rc == kUnmapped) continue;
    v.tris.push_back(ra), v.tris.push_back(rb), v.tris.push_back(rc);
  }
  for (uint32_t i = 0; i < n; ++i) cache.remap[i] = kUnmapped;
}

// The tetrahedral lens: boundary faces of live tets, split into the original outer surface
// (no neighbour in the mesh) and the faces sculpting exposed (a removed neighbour).
void fill_tet_lens(BodyView& outer, BodyView& inner, const Particles& p, const TetTopology& topo,
                   SnapshotFillCache& cache) {
  outer.piece.clear(), inner.piece.clear();  // one piece
  if (cache.lens_topology == &topo && cache.lens_alive == topo.alive_count &&
      cache.lens_particles == p.x.size()) {
    // The snapshot slot may hold another fill's views (triple buffer): copy the cached ones.
    BodyView* views[2] = {&outer, &inner};
    for (size_t k = 0; k < 2; ++k) {
      BodyView& v = *views[k];
      v.tris.assign(cache.lens_tris[k].begin(), cache.lens_tris[k].end());
      v.xyz.resize(3 * cache.lens_nodes[k].size());
      for (size_t m = 0; m < cache.lens_nodes[k].size(); ++m) {
        const uint32_t i = cache.lens_nodes[k][m];
        v.xyz[3 * m] = p.x[i], v.xyz[3 * m + 1] = p.y[i], v.xyz[3 * m + 2] = p.z[i];
      }
    }
    return;
  }
  cache.faces.clear();
  cache.interior.clear();
  for (uint32_t t : topo.surface) {
    const auto& v = topo.vertices[t];
    for (int k = 0; k < 4; ++k) {
      const uint32_t n = topo.neighbours[t][k];
      if (n != kNoTet && topo.alive[n]) continue;
      const std::array<uint32_t, 3> f = {v[kTetFaceCorners[k][0]], v[kTetFaceCorners[k][1]],
                                         v[kTetFaceCorners[k][2]]};
      (n == kNoTet ? cache.faces : cache.interior).push_back(f);
    }
  }
  compact_faces(outer, cache.faces, p.x, p.y, p.z, cache);
  cache.lens_nodes[0].assign(cache.touched.begin(), cache.touched.end());
  compact_faces(inner, cache.interior, p.x, p.y, p.z, cache);
  cache.lens_nodes[1].assign(cache.touched.begin(), cache.touched.end());
  cache.lens_tris[0].assign(outer.tris.begin(), outer.tris.end());
  cache.lens_tris[1].assign(inner.tris.begin(), inner.tris.end());
  cache.lens_topology = &topo;
  cache.lens_alive = topo.alive_count;
  cache.lens_particles = p.x.size();
}

// Each vertex's fragment, wrapped to a byte, so the renderer tints the pieces apart: a face node's
// cell's label; a ring centre (no face of its own) takes that of a face node of its triangles.
// Call right after compact_faces: cache.touched lists the view's nodes in their compacted order.
void fill_pieces(BodyView& v, const simplex::BoundarySurface& s, std::span<const uint32_t> labels,
                 const SnapshotFillCache& cache) {
  constexpr uint8_t kUnknown = 0xFF;
  v.piece.assign(cache.touched.size(), kUnknown);
  for (size_t m = 0; m < cache.touched.size(); ++m) {
    const uint32_t node = cache.touched[m];
    const uint32_t face = node < s.node_face.size() ? s.node_face[node] : kNoSimplex;
    const uint32_t cell = face == kNoSimplex ? kNoSimplex : simplex_face_cell(face);
    if (cell < labels.size() && labels[cell] != kNoSimplex)
      v.piece[m] = static_cast<uint8_t>(labels[cell] % kUnknown);
  }
  for (size_t t = 0; t + 2 < v.tris.size(); t += 3)
    for (int k = 0; k < 3; ++k) {
      uint8_t& p = v.piece[v.tris[t + k]];
      if (p != kUnknown) continue;
      for (int j = 1; j < 3 && p == kUnknown; ++j) p = v.piece[v.tris[t + (k + j) % 3]];
    }
}

// The fragmenting lens: the simplex boundary surface (nodes at the external faces' centres).
void fill_fragment_lens(BodyView& outer, BodyView& inner, const SimplexCells& cells,
                        std::span<const uint32_t> labels, SnapshotFillCache& cache) {
  const uint32_t faces = cells.size() * 4;
  if (cache.face_was_external.size() != faces) {
    cache.face_was_external.assign(faces, 0);
    for (uint32_t c = 0; c < cells.size(); ++c)
      for (uint32_t k = 0; k < 4; ++k)
        cache.face_was_external[simplex_face_id(c, k)] = cells.is_external(c, k) ? 1 : 0;
  }
  simplex::BoundarySurface& s = cache.boundary;
  simplex::build_boundary_surface(cells, s);
  cache.faces.clear();
  cache.interior.clear();
  for (const auto& tri : s.triangles) {
    bool original = true;
    for (uint32_t node : tri) {
      const uint32_t f = node < s.node_face.size() ? s.node_face[node] : kNoSimplex;
      if (f != kNoSimplex && f < faces && !cache.face_was_external[f]) original = false;
    }
    (original ? cache.faces : cache.interior).push_back(tri);
  }
  compact_faces(outer, cache.faces, s.x, s.y, s.z, cache);
  fill_pieces(outer, s, labels, cache);
  compact_faces(inner, cache.interior, s.x, s.y, s.z, cache);
  fill_pieces(inner, s, labels, cache);
}

void fill_guidance(Scene& scene, render::RenderSnapshot& snap, SnapshotFillCache& cache) {
  const Guidance& g = scene.drill.guidance;
  render::GuidanceView& out = snap.guidance;
  out.grasp_site_mm = g.grasp_site_mm;
  out.puncture_site_mm = g.puncture_site_mm;
  out.rhexis_centre_mm.reset();
  out.rhexis_diameter_mm = 0;
  if (g.rhexis_circle) {
    out.rhexis_centre_mm = g.rhexis_circle->centre_mm;
    out.rhexis_diameter_mm = g.rhexis_circle->diameter_mm;
  }
  out.trench_centre_mm.reset();
  out.trench_first_angle_deg = out.trench_arm_mm = 0;
  if (g.trench_cross) {
    out.trench_centre_mm = g.trench_cross->centre_mm;
    out.trench_first_angle_deg = g.trench_cross->first_angle_deg;
    out.trench_arm_mm = g.trench_cross->arm_length_mm;
  }
  out.ports_mm.clear();
  if (const PortsRecord* r = ports_record(scene)) {
    for (const EyePort& p : r->ports) out.ports_mm.push_back(p.centre_mm);
    return;
  }
  if (!cache.ports_made) {
    // The incision sites as ports in the globe's rest pose (made once: default_ports allocates).
    cache.ports_made = true;
    if (g.incision_site) {
      const double side = g.side_port ? g.side_port->clock_hour : g.incision_site->clock_hour;
      try {
        const auto ports = default_ports(scene.params, g.incision_site->clock_hour, side);
        for (size_t i = 0; i < ports.size() && (i == 0 || g.side_port); ++i)
          cache.ports.push_back(ports[i].centre_mm);
      } catch (const InputError&) {
        // An eye whose port falls outside the cornea: no port cue (the drill still runs).
      }
    }
  }
  out.ports_mm.assign(cache.ports.begin(), cache.ports.end());
}

}  // namespace

void fill_snapshot(Scene& scene, render::RenderSnapshot& snap) {
  snap.frame = scene.frame;
  snap.time_s = scene.time_s;
  if (scene.bodies.empty()) {
    snap.bodies.clear();
    snap.tools.clear();
    return;
  }
  World& w = scene.world;
  SnapshotFillCache* cache = w.get<SnapshotFillCache>(scene.bodies.front());
  if (!cache) cache = &w.add(scene.bodies.front(), SnapshotFillCache{});

  size_t n = 0;
  for (Entity e : scene.bodies) {
    const BodyPart part = w.at<Body>(e).part;
    const std::string& name = w.name(e);
    if (part == BodyPart::Lens) {
      const size_t a = n++, b = n++;
      // The second view first: it may grow the vector, which would move the first.
      BodyView& inner = view_at(snap, *cache, b, "lens.interior", Look::LensInterior);
      BodyView& outer = view_at(snap, *cache, a, name, Look::LensSurface);
      if (const LensFragments* lf = w.get<LensFragments>(e)) {
        fill_fragment_lens(outer, inner, lf->lens.cells, lf->lens.fragments.label, *cache);
      } else if (const LensSculpting* ls = w.get<LensSculpting>(e)) {
        fill_tet_lens(outer, inner, w.at<Particles>(e), ls->topology, *cache);
      } else {
        outer.xyz.clear(), outer.tris.clear(), inner.xyz.clear(), inner.tris.clear();
      }
      if (cache->reflex_attenuation < 0) cache->reflex_attenuation = reflex_attenuation(scene);
      outer.reflex_attenuation_per_mm = inner.reflex_attenuation_per_mm = cache->reflex_attenuation;
      finish_view(outer, cache->views[a], false, *cache);
      finish_view(inner, cache->views[b], false, *cache);
      continue;
    }
    const Particles* p = w.get<Particles>(e);
    const Triangles* t = w.get<Triangles>(e);
    if (!p || !t) continue;
    const size_t i = n++;
    BodyView& v = view_at(snap, *cache, i, name, look_of(part));
    fill_surface(v, *p, *t, *cache);
    finish_view(v, cache->views[i], part == BodyPart::Capsule, *cache);
  }
  snap.bodies.resize(n);  // shrinks only (a scene's body set is fixed): no allocation

  // Drawn opaque first, translucent last: the renderer sorts by look if it needs more.
  snap.tools.resize(scene.tools.size());
  if (!cache->eye) {
    cache->eye = eye::eye_geometry(scene.params);
    cache->has_capsule = scene.body(BodyPart::Capsule).has_value();
  }
  for (size_t k = 0; k < scene.tools.size(); ++k) {
    const Entity e = scene.tools[k];
    const Tool& tool = w.at<Tool>(e);
    const ToolState& pose = w.at<ToolState>(e);
    render::ToolView& tv = snap.tools[k];
    tv.kind = tool.kind;
    tv.hand = tool.hand;
    tv.tip_mm = pose.pos;
    tv.quat = pose.quat;
    tv.grip = pose.grip;
    tv.pedal = pose.pedal;
    tv.selected = false;  // the trainer session marks the desktop input's hand
    const ToolGrasp* g = w.get<ToolGrasp>(e);
    tv.in_contact = g && g->capsule.holding();
    const TipHeight h = tip_height(*cache->eye, cache->has_capsule, pose.pos);
    tv.height_mm = h.height_mm;
    tv.under = h.under;
  }
  fill_guidance(scene, snap, *cache);
  const PortsRecord* ports = ports_record(scene);
  snap.globe_rotation = ports ? ports->globe.rotation : Quat::Identity();
}

}  // namespace phaco
