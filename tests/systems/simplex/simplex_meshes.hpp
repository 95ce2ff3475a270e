#pragma once
// Small tet meshes and a brute-force flood fill for the simplex tests.
#include <algorithm>
#include <array>
#include <cstdint>
#include <deque>
#include <random>
#include <vector>

#include "components/simplices.hpp"
#include "engine/core/mesh_data.hpp"

namespace phaco::simplex::testing {

inline void orient_positive(TetMesh& m) {
  for (auto& t : m.tets) {
    const Vec3& a = m.vertices[t[0]];
    if ((m.vertices[t[1]] - a).dot((m.vertices[t[2]] - a).cross(m.vertices[t[3]] - a)) < 0)
      std::swap(t[2], t[3]);
  }
  m.region.assign(m.tets.size(), 0);
}

inline TetMesh one_tet() {
  TetMesh m;
  m.vertices = {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0), Vec3(0, 0, 1)};
  m.tets = {{0, 1, 2, 3}};
  orient_positive(m);
  return m;
}

// Seed 002 Fig. 4: two tets sharing the face (0, 1, 2).
inline TetMesh two_tets() {
  TetMesh m;
  m.vertices = {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0), Vec3(0.3, 0.3, 1), Vec3(0.3, 0.3, -1)};
  m.tets = {{0, 1, 2, 3}, {0, 2, 1, 4}};
  orient_positive(m);
  return m;
}

inline Vec3 corner(int i) {
  return Vec3(i & 1, (i >> 1) & 1, (i >> 2) & 1);
}

// Unit cube as 5 tets: four corner tets (three faces on the cube each) around a central one.
inline TetMesh cube_five() {
  TetMesh m;
  for (int i = 0; i < 8; ++i) m.vertices.push_back(corner(i));
  // Corners 0, 3, 5, 6 span the central tet; 1, 2, 4, 7 are cut off.
  m.tets = {{0, 3, 5, 6}, {1, 0, 3, 5}, {2, 0, 3, 6}, {4, 0, 5, 6}, {7, 3, 5, 6}};
  orient_positive(m);
  return m;
}

// An n×n×n grid of unit cubes, each split into 6 tets about its diagonal (Kuhn): every tet has two
// faces on its cube's surface and shares two with tets of the same cube.
inline TetMesh kuhn_grid(int n) {
  TetMesh m;
  auto id = [n](int x, int y, int z) {
    return static_cast<uint32_t>((z * (n + 1) + y) * (n + 1) + x);
  };
  for (int z = 0; z <= n; ++z)
    for (int y = 0; y <= n; ++y)
      for (int x = 0; x <= n; ++x) m.vertices.push_back(Vec3(x, y, z));
  const int perms[6][3] = {{0, 1, 2}, {0, 2, 1}, {1, 0, 2}, {1, 2, 0}, {2, 0, 1}, {2, 1, 0}};
  for (int z = 0; z < n; ++z)
    for (int y = 0; y < n; ++y)
      for (int x = 0; x < n; ++x)
        for (const auto& p : perms) {
          std::array<int, 3> c{x, y, z};
          std::array<uint32_t, 4> t{};
          t[0] = id(c[0], c[1], c[2]);
          for (int s = 0; s < 3; ++s) {
            ++c[p[s]];
            t[s + 1] = id(c[0], c[1], c[2]);
          }
          m.tets.push_back(t);
        }
  orient_positive(m);
  return m;
}

// Brute-force components: breadth-first over shared faces found by sorting the alive tets' vertex
// triples (independent of the neighbour columns). Labels in order of the smallest cell id.
inline std::vector<uint32_t> brute_force_labels(const SimplexCells& cells) {
  const uint32_t n = cells.size();
  std::vector<std::pair<std::array<uint32_t, 3>, uint32_t>> faces;
  for (uint32_t c = 0; c < n; ++c) {
    if (!cells.alive[c]) continue;
    for (int skip = 0; skip < 4; ++skip) {
      std::array<uint32_t, 3> key{};
      int j = 0;
      for (int v = 0; v < 4; ++v)
        if (v != skip) key[j++] = cells.tet[c][v];
      std::sort(key.begin(), key.end());
      faces.push_back({key, c});
    }
  }
  std::sort(faces.begin(), faces.end());
  std::vector<std::vector<uint32_t>> adjacent(n);
  for (size_t i = 0; i + 1 < faces.size(); ++i)
    if (faces[i].first == faces[i + 1].first) {
      adjacent[faces[i].second].push_back(faces[i + 1].second);
      adjacent[faces[i + 1].second].push_back(faces[i].second);
    }
  std::vector<uint32_t> label(n, kNoSimplex);
  uint32_t next = 0;
  for (uint32_t s = 0; s < n; ++s) {
    if (!cells.alive[s] || label[s] != kNoSimplex) continue;
    std::deque<uint32_t> queue{s};
    label[s] = next;
    while (!queue.empty()) {
      const uint32_t c = queue.front();
      queue.pop_front();
      for (uint32_t d : adjacent[c])
        if (label[d] == kNoSimplex) label[d] = next, queue.push_back(d);
    }
    ++next;
  }
  return label;
}

inline std::vector<uint32_t> random_order(uint32_t n, std::mt19937& rng) {
  std::vector<uint32_t> order(n);
  for (uint32_t i = 0; i < n; ++i) order[i] = i;
  for (uint32_t i = n; i > 1; --i) std::swap(order[i - 1], order[rng() % i]);
  return order;
}

}  // namespace phaco::simplex::testing
