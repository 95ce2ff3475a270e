#include "systems/simplex/simplex_cells.hpp"

#include <algorithm>
#include <span>
#include <stdexcept>
#include <string>
#include <vector>

namespace phaco::simplex {
namespace {

// The topology columns the walk and the rebuild need; the check runs them on rebuilt neighbours.
struct TopologyView {
  const std::array<uint32_t, 4>* tet;
  const std::array<uint32_t, 4>* neighbour;
  const std::array<uint8_t, 4>* neighbour_face;
  const uint8_t* alive;
  uint32_t cells;
};

TopologyView view_of(const SimplexCells& c) {
  return {c.tet.data(), c.neighbour.data(), c.neighbour_face.data(), c.alive.data(), c.size()};
}

uint32_t local_index(const std::array<uint32_t, 4>& tet, uint32_t vertex) {
  for (uint32_t i = 0; i < 4; ++i)
    if (tet[i] == vertex) return i;
  return 4;
}

// State (d, h, o): face h of cell d holds the edge, o is h's corner off the edge (see header).
uint32_t walk(const TopologyView& v, uint32_t face_id, uint32_t slot, uint32_t* partner_slot,
              uint32_t max_steps) {
  uint32_t d = simplex_face_cell(face_id);
  uint32_t o = simplex_face_local(face_id);
  uint32_t h = kTetFaceCorners[o][slot];
  for (uint32_t step = 0; step < max_steps; ++step) {
    const uint32_t next = v.neighbour[d][h];
    if (next == kNoSimplex) {
      *partner_slot = kTetCornerSlot[h][o];
      return simplex_face_id(d, h);
    }
    const uint32_t o_next = local_index(v.tet[next], v.tet[d][o]);
    if (o_next > 3) return kNoSimplex;
    o = v.neighbour_face[d][h];
    h = o_next;
    d = next;
  }
  return kNoSimplex;
}

uint64_t edge_key(uint32_t a, uint32_t b) {
  return a < b ? (uint64_t{a} << 32) | b : (uint64_t{b} << 32) | a;
}

struct EdgeRecord {
  uint64_t key;
  uint32_t face_id;
  uint32_t slot;
};

// Construction loop 3 over the view's external faces: a boundary edge met twice pairs its two
// faces; any other count (non-manifold) takes the walk through the solid.
void links_from(const TopologyView& v, std::vector<std::array<uint32_t, 12>>& links) {
  links.assign(v.cells, {});
  for (auto& l : links) l.fill(kNoSimplex);
  std::vector<EdgeRecord> records;
  for (uint32_t c = 0; c < v.cells; ++c) {
    if (!v.alive[c]) continue;
    for (uint32_t k = 0; k < 4; ++k) {
      if (v.neighbour[c][k] != kNoSimplex) continue;
      for (uint32_t j = 0; j < 3; ++j) {
        const uint32_t a = v.tet[c][kTetFaceCorners[k][(j + 1) % 3]];
        const uint32_t b = v.tet[c][kTetFaceCorners[k][(j + 2) % 3]];
        records.push_back({edge_key(a, b), simplex_face_id(c, k), j});
      }
    }
  }
  std::sort(records.begin(), records.end(), [](const EdgeRecord& p, const EdgeRecord& q) {
    return p.key != q.key           ? p.key < q.key
           : p.face_id != q.face_id ? p.face_id < q.face_id
                                    : p.slot < q.slot;
  });
  for (size_t i = 0; i < records.size();) {
    size_t end = i + 1;
    while (end < records.size() && records[end].key == records[i].key) ++end;
    if (end - i == 2) {
      const EdgeRecord& p = records[i];
      const EdgeRecord& q = records[i + 1];
      links[simplex_face_cell(p.face_id)][3 * simplex_face_local(p.face_id) + p.slot] = q.face_id;
      links[simplex_face_cell(q.face_id)][3 * simplex_face_local(q.face_id) + q.slot] = p.face_id;
    } else {
      for (size_t r = i; r < end; ++r) {
        uint32_t ps = 0;
        const EdgeRecord& p = records[r];
        links[simplex_face_cell(p.face_id)][3 * simplex_face_local(p.face_id) + p.slot] =
            walk(v, p.face_id, p.slot, &ps, 4096);
      }
    }
    i = end;
  }
}

struct FaceRecord {
  std::array<uint32_t, 3> key;  // sorted vertex ids
  uint32_t face_id;
};

// Construction loops 1–2 on the vertex triples: faces met twice are shared. Returns the number of
// triples met more than twice (0 for a valid mesh).
uint32_t connect_shared_faces(const std::vector<std::array<uint32_t, 4>>& tets,
                              const uint8_t* alive, std::vector<std::array<uint32_t, 4>>& neighbour,
                              std::vector<std::array<uint8_t, 4>>& neighbour_face) {
  const uint32_t n = static_cast<uint32_t>(tets.size());
  neighbour.assign(n, {kNoSimplex, kNoSimplex, kNoSimplex, kNoSimplex});
  neighbour_face.assign(n, {0, 0, 0, 0});
  std::vector<FaceRecord> faces;
  faces.reserve(size_t{4} * n);
  for (uint32_t c = 0; c < n; ++c) {
    if (alive && !alive[c]) continue;
    for (uint32_t k = 0; k < 4; ++k) {
      std::array<uint32_t, 3> key{tets[c][kTetFaceCorners[k][0]], tets[c][kTetFaceCorners[k][1]],
                                  tets[c][kTetFaceCorners[k][2]]};
      std::sort(key.begin(), key.end());
      faces.push_back({key, simplex_face_id(c, k)});
    }
  }
  std::sort(faces.begin(), faces.end(), [](const FaceRecord& p, const FaceRecord& q) {
    return p.key != q.key ? p.key < q.key : p.face_id < q.face_id;
  });
  uint32_t over_shared = 0;
  for (size_t i = 0; i < faces.size();) {
    size_t end = i + 1;
    while (end < faces.size() && faces[end].key == faces[i].key) ++end;
    if (end - i == 2) {
      const uint32_t p = faces[i].face_id, q = faces[i + 1].face_id;
      neighbour[simplex_face_cell(p)][simplex_face_local(p)] = simplex_face_cell(q);
      neighbour_face[simplex_face_cell(p)][simplex_face_local(p)] =
          static_cast<uint8_t>(simplex_face_local(q));
      neighbour[simplex_face_cell(q)][simplex_face_local(q)] = simplex_face_cell(p);
      neighbour_face[simplex_face_cell(q)][simplex_face_local(q)] =
          static_cast<uint8_t>(simplex_face_local(p));
    } else if (end - i > 2) {
      ++over_shared;
    }
    i = end;
  }
  return over_shared;
}

// Boundary links of faces that just became external (a removal's or a crack's): each finds its
// partner on each edge through the solid, and the partner links back.
void link_new_faces(SimplexCells& cells, std::span<const uint32_t> new_faces) {
  const TopologyView v = view_of(cells);
  for (const uint32_t f : new_faces) {
    auto& own = cells.boundary_link[simplex_face_cell(f)];
    for (uint32_t j = 0; j < 3; ++j) {
      uint32_t ps = 0;
      const uint32_t partner = walk(v, f, j, &ps, 4096);
      own[3 * simplex_face_local(f) + j] = partner;
      if (partner != kNoSimplex)
        cells.boundary_link[simplex_face_cell(partner)][3 * simplex_face_local(partner) + ps] = f;
    }
  }
}

}  // namespace

SimplexCells build_cells(const TetMesh& mesh, double density_kg_mm3) {
  const uint32_t n = static_cast<uint32_t>(mesh.tets.size());
  SimplexCells cells;
  cells.x.resize(n), cells.y.resize(n), cells.z.resize(n);
  cells.rest_x.resize(n), cells.rest_y.resize(n), cells.rest_z.resize(n);
  cells.volume.resize(n), cells.mass.resize(n);
  cells.alive.assign(n, 1);
  cells.region.assign(n, 0);
  cells.tet.resize(n);
  cells.face_x.resize(size_t{4} * n), cells.face_y.resize(size_t{4} * n),
      cells.face_z.resize(size_t{4} * n);
  // Loop 1: centres, volumes, face centres (the face keys are gathered in connect_shared_faces).
  for (uint32_t c = 0; c < n; ++c) {
    std::array<uint32_t, 4> t = mesh.tets[c];
    for (uint32_t vtx : t)
      if (vtx >= mesh.vertices.size())
        throw std::invalid_argument("build_cells: tet " + std::to_string(c) + " names vertex " +
                                    std::to_string(vtx) + " beyond the mesh's " +
                                    std::to_string(mesh.vertices.size()));
    double six_v = (mesh.vertices[t[1]] - mesh.vertices[t[0]])
                       .dot((mesh.vertices[t[2]] - mesh.vertices[t[0]])
                                .cross(mesh.vertices[t[3]] - mesh.vertices[t[0]]));
    if (six_v < 0)
      std::swap(t[2], t[3]), six_v = -six_v;  // the face tables assume positive orientation
    cells.tet[c] = t;
    const Vec3 centre = 0.25 * (mesh.vertices[t[0]] + mesh.vertices[t[1]] + mesh.vertices[t[2]] +
                                mesh.vertices[t[3]]);
    cells.x[c] = cells.rest_x[c] = static_cast<float>(centre.x());
    cells.y[c] = cells.rest_y[c] = static_cast<float>(centre.y());
    cells.z[c] = cells.rest_z[c] = static_cast<float>(centre.z());
    cells.volume[c] = static_cast<float>(six_v / 6.0);
    cells.mass[c] = static_cast<float>(density_kg_mm3 * six_v / 6.0);
    if (c < mesh.region.size()) cells.region[c] = mesh.region[c];
    for (uint32_t k = 0; k < 4; ++k) {
      const auto& fc = kTetFaceCorners[k];
      const Vec3 f =
          (mesh.vertices[t[fc[0]]] + mesh.vertices[t[fc[1]]] + mesh.vertices[t[fc[2]]]) / 3.0;
      cells.face_x[4 * c + k] = static_cast<float>(f.x());
      cells.face_y[4 * c + k] = static_cast<float>(f.y());
      cells.face_z[4 * c + k] = static_cast<float>(f.z());
    }
  }
  // Loop 2: shared faces → internal connections.
  if (connect_shared_faces(cells.tet, nullptr, cells.neighbour, cells.neighbour_face) != 0)
    throw std::invalid_argument(
        "build_cells: a face is shared by more than two tets (not a tet mesh)");
  // Loop 3: non-shared faces → boundary links.
  links_from(view_of(cells), cells.boundary_link);
  cells.alive_count = n;
  return cells;
}

uint32_t walk_boundary_partner(const SimplexCells& cells, uint32_t face_id, uint32_t slot,
                               uint32_t* partner_slot, uint32_t max_steps) {
  return walk(view_of(cells), face_id, slot, partner_slot, max_steps);
}

Removal remove_cell(SimplexCells& cells, uint32_t cell) {
  Removal r;
  r.cell = cell;
  if (cell >= cells.size() || !cells.alive[cell]) return r;
  r.removed = true;
  cells.alive[cell] = 0;
  --cells.alive_count;
  // Internal connections: each deleted link becomes an external face of the neighbour.
  std::array<uint32_t, 4> new_faces{};
  uint32_t new_count = 0, external = 0;
  for (uint32_t k = 0; k < 4; ++k) {
    const uint32_t n = cells.neighbour[cell][k];
    if (n == kNoSimplex) {
      ++external;
      continue;
    }
    const uint32_t f = cells.neighbour_face[cell][k];
    cells.neighbour[n][f] = kNoSimplex;
    r.neighbours[k] = n;
    r.new_faces[k] = simplex_face_id(n, f);
    new_faces[new_count++] = simplex_face_id(n, f);
    cells.neighbour[cell][k] = kNoSimplex;
  }
  cells.boundary_link[cell].fill(kNoSimplex);
  r.kind = static_cast<RemovalCase>(external);
  r.alive_neighbours = static_cast<uint8_t>(new_count);
  r.may_split = new_count >= 2;
  link_new_faces(cells, std::span<const uint32_t>(new_faces.data(), new_count));
  return r;
}

bool break_link(SimplexCells& cells, uint32_t cell, uint32_t face) {
  if (cell >= cells.size() || face > 3 || !cells.alive[cell]) return false;
  const uint32_t n = cells.neighbour[cell][face];
  if (n == kNoSimplex) return false;
  const uint32_t f = cells.neighbour_face[cell][face];
  cells.neighbour[cell][face] = kNoSimplex;
  cells.neighbour[n][f] = kNoSimplex;
  const std::array<uint32_t, 2> new_faces{simplex_face_id(cell, face), simplex_face_id(n, f)};
  link_new_faces(cells, new_faces);
  return true;
}

uint32_t count_external_faces(const SimplexCells& cells) {
  uint32_t count = 0;
  for (uint32_t c = 0; c < cells.size(); ++c)
    if (cells.alive[c])
      for (uint32_t k = 0; k < 4; ++k) count += cells.neighbour[c][k] == kNoSimplex;
  return count;
}

void rebuild_boundary_links(const SimplexCells& cells,
                            std::vector<std::array<uint32_t, 12>>& links) {
  links_from(view_of(cells), links);
}

BoundaryCheck check_boundary(const SimplexCells& cells) {
  BoundaryCheck report;
  const uint32_t n = cells.size();
  std::vector<std::array<uint32_t, 4>> neighbour;
  std::vector<std::array<uint8_t, 4>> neighbour_face;
  report.neighbour_mismatches =
      connect_shared_faces(cells.tet, cells.alive.data(), neighbour, neighbour_face);
  std::vector<std::array<uint32_t, 12>> links;
  const TopologyView rebuilt{cells.tet.data(), neighbour.data(), neighbour_face.data(),
                             cells.alive.data(), n};
  links_from(rebuilt, links);

  for (uint32_t c = 0; c < n; ++c) {
    if (!cells.alive[c]) {
      for (uint32_t k = 0; k < 4; ++k) report.stale_entries += cells.neighbour[c][k] != kNoSimplex;
      for (uint32_t s = 0; s < 12; ++s)
        report.stale_entries += cells.boundary_link[c][s] != kNoSimplex;
      continue;
    }
    ++report.alive_cells;
    for (uint32_t k = 0; k < 4; ++k) {
      const uint32_t nb = cells.neighbour[c][k];
      report.external_faces += nb == kNoSimplex;
      report.rebuilt_external_faces += neighbour[c][k] == kNoSimplex;
      if (nb != neighbour[c][k] ||
          (nb != kNoSimplex && cells.neighbour_face[c][k] != neighbour_face[c][k]))
        ++report.neighbour_mismatches;
      for (uint32_t j = 0; j < 3; ++j) {
        const uint32_t got = cells.boundary_link[c][3 * k + j];
        if (got != links[c][3 * k + j]) ++report.link_mismatches;
        if (nb != kNoSimplex) {
          report.stale_entries += got != kNoSimplex;
          continue;
        }
        // The partner must be an external face holding the same edge and pointing back across it.
        const uint32_t u = cells.tet[c][kTetFaceCorners[k][(j + 1) % 3]];
        const uint32_t w = cells.tet[c][kTetFaceCorners[k][(j + 2) % 3]];
        bool symmetric = false;
        if (got != kNoSimplex && simplex_face_cell(got) < n) {
          const uint32_t pc = simplex_face_cell(got), pk = simplex_face_local(got);
          if (cells.alive[pc] && cells.neighbour[pc][pk] == kNoSimplex)
            for (uint32_t pj = 0; pj < 3; ++pj) {
              const uint32_t pu = cells.tet[pc][kTetFaceCorners[pk][(pj + 1) % 3]];
              const uint32_t pw = cells.tet[pc][kTetFaceCorners[pk][(pj + 2) % 3]];
              if (edge_key(pu, pw) == edge_key(u, w))
                symmetric = cells.boundary_link[pc][3 * pk + pj] == simplex_face_id(c, k);
            }
        }
        report.asymmetric_links += !symmetric;
      }
    }
  }
  const uint32_t counted = report.alive_cells;
  report.alive_count_error =
      counted > cells.alive_count ? counted - cells.alive_count : cells.alive_count - counted;
  return report;
}

}  // namespace phaco::simplex
