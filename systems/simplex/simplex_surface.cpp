#include "systems/simplex/simplex_surface.hpp"

#include <cmath>

namespace phaco::simplex {

void build_boundary_surface(const SimplexCells& cells, BoundarySurface& out) {
  const uint32_t n = cells.size();
  out.node_face.clear(), out.x.clear(), out.y.clear(), out.z.clear();
  out.triangles.clear(), out.tri_nx.clear(), out.tri_ny.clear(), out.tri_nz.clear();
  out.broken_rings = 0;
  out.node_of_face.assign(size_t{4} * n, kNoSimplex);
  // Loop 1: a node for every external face.
  for (uint32_t c = 0; c < n; ++c) {
    if (!cells.alive[c]) continue;
    for (uint32_t k = 0; k < 4; ++k) {
      if (cells.neighbour[c][k] != kNoSimplex) continue;
      const uint32_t f = simplex_face_id(c, k);
      out.node_of_face[f] = static_cast<uint32_t>(out.node_face.size());
      out.node_face.push_back(f);
      out.x.push_back(cells.x[c] + (cells.face_x[f] - cells.rest_x[c]));
      out.y.push_back(cells.y[c] + (cells.face_y[f] - cells.rest_y[c]));
      out.z.push_back(cells.z[c] + (cells.face_z[f] - cells.rest_z[c]));
    }
  }
  const uint32_t face_nodes = static_cast<uint32_t>(out.node_face.size());
  out.face_nodes = face_nodes;
  out.visited.assign(face_nodes, 0);
  // Loop 2: the ring of faces about each (node, corner) not yet visited.
  for (uint32_t start = 0; start < face_nodes; ++start) {
    for (uint32_t p0 = 0; p0 < 3; ++p0) {
      if (out.visited[start] & (1u << p0)) continue;
      out.ring.clear();
      uint32_t face = out.node_face[start], p = p0;
      bool closed = false;
      for (uint32_t step = 0; step < 4096; ++step) {
        const uint32_t node = out.node_of_face[face];
        if (node == kNoSimplex || (out.visited[node] & (1u << p))) break;
        out.visited[node] |= static_cast<uint8_t>(1u << p);
        out.ring.push_back(node);
        const uint32_t c = simplex_face_cell(face), k = simplex_face_local(face);
        const uint32_t vertex = cells.tet[c][kTetFaceCorners[k][p]];
        const uint32_t next = cells.boundary_link[c][3 * k + (p + 2) % 3];  // edge (p, p+1)
        if (next == kNoSimplex) break;
        const uint32_t nc = simplex_face_cell(next), nk = simplex_face_local(next);
        uint32_t np = 3;
        for (uint32_t q = 0; q < 3; ++q)
          if (cells.tet[nc][kTetFaceCorners[nk][q]] == vertex) np = q;
        if (np == 3) break;
        face = next, p = np;
        if (face == out.node_face[start] && p == p0) {
          closed = true;
          break;
        }
      }
      if (!closed) {
        ++out.broken_rings;
        continue;
      }
      // The ring turns clockwise seen from outside; emit it counter-clockwise. A ring of three
      // is one triangle; a longer one is fanned from a node at its centre (fanning from one of
      // its faces would put the same diagonal in the rings of both ends of a non-manifold edge).
      const auto& r = out.ring;
      if (r.size() == 3) {
        out.triangles.push_back({r[0], r[2], r[1]});
        continue;
      }
      float cx = 0, cy = 0, cz = 0;
      for (uint32_t node : r) cx += out.x[node], cy += out.y[node], cz += out.z[node];
      const float inv = 1.0f / static_cast<float>(r.size());
      const uint32_t centre = static_cast<uint32_t>(out.x.size());
      out.x.push_back(cx * inv), out.y.push_back(cy * inv), out.z.push_back(cz * inv);
      out.node_face.push_back(kNoSimplex);
      for (size_t i = 0; i < r.size(); ++i)
        out.triangles.push_back({centre, r[(i + 1) % r.size()], r[i]});
    }
  }
  // Loop 3: normals.
  const uint32_t nodes = static_cast<uint32_t>(out.x.size());
  out.nx.assign(nodes, 0.0f), out.ny.assign(nodes, 0.0f), out.nz.assign(nodes, 0.0f);
  for (const auto& t : out.triangles) {
    const Vec3f a(out.x[t[0]], out.y[t[0]], out.z[t[0]]);
    const Vec3f b(out.x[t[1]], out.y[t[1]], out.z[t[1]]);
    const Vec3f cc(out.x[t[2]], out.y[t[2]], out.z[t[2]]);
    const Vec3f area2 = (b - a).cross(cc - a);
    const float len = area2.norm();
    const Vec3f unit = len > 0.0f ? Vec3f(area2 / len) : Vec3f::Zero();
    out.tri_nx.push_back(unit.x()), out.tri_ny.push_back(unit.y()), out.tri_nz.push_back(unit.z());
    for (uint32_t v : t) out.nx[v] += area2.x(), out.ny[v] += area2.y(), out.nz[v] += area2.z();
  }
  for (uint32_t i = 0; i < nodes; ++i) {
    const float len =
        std::sqrt(out.nx[i] * out.nx[i] + out.ny[i] * out.ny[i] + out.nz[i] * out.nz[i]);
    if (len > 0.0f) out.nx[i] /= len, out.ny[i] /= len, out.nz[i] /= len;
  }
}

void extract_external_faces(const SimplexCells& cells, std::span<const Vec3> vertices,
                            SurfaceMesh& out) {
  out.vertices.assign(vertices.begin(), vertices.end());
  out.triangles.clear();
  for (uint32_t c = 0; c < cells.size(); ++c) {
    if (!cells.alive[c]) continue;
    for (uint32_t k = 0; k < 4; ++k)
      if (cells.neighbour[c][k] == kNoSimplex)
        out.triangles.push_back({cells.tet[c][kTetFaceCorners[k][0]],
                                 cells.tet[c][kTetFaceCorners[k][1]],
                                 cells.tet[c][kTetFaceCorners[k][2]]});
  }
}

}  // namespace phaco::simplex
