#pragma once
// Helpers shared by the eye tests: scratch directories and simple mesh measurements.
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <filesystem>
#include <numbers>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "engine/core/mesh_data.hpp"

namespace phaco::test {

// A fresh directory under the system temp dir, removed when the object goes out of scope.
class ScratchDir {
 public:
  explicit ScratchDir(const std::string& tag) {
    static std::atomic<int> counter{0};
    path_ = std::filesystem::temp_directory_path() /
            ("phaco_" + tag + "_" + std::to_string(::getpid()) + "_" + std::to_string(counter++));
    std::filesystem::remove_all(path_);
    std::filesystem::create_directories(path_);
  }
  ~ScratchDir() {
    std::error_code ec;
    std::filesystem::remove_all(path_, ec);
  }
  ScratchDir(const ScratchDir&) = delete;
  ScratchDir& operator=(const ScratchDir&) = delete;
  const std::filesystem::path& path() const { return path_; }

 private:
  std::filesystem::path path_;
};

// Number of distinct neighbours of each vertex.
inline std::vector<size_t> valences(const SurfaceMesh& mesh) {
  std::vector<std::set<uint32_t>> nb(mesh.vertices.size());
  for (const auto& t : mesh.triangles) {
    for (int k = 0; k < 3; ++k) {
      nb[t[k]].insert(t[(k + 1) % 3]);
      nb[t[k]].insert(t[(k + 2) % 3]);
    }
  }
  std::vector<size_t> out;
  for (const auto& s : nb) out.push_back(s.size());
  return out;
}

// Vertices on an edge used by one triangle only.
inline std::vector<bool> boundary_vertices(const SurfaceMesh& mesh) {
  std::vector<std::pair<uint32_t, uint32_t>> edges;
  for (const auto& t : mesh.triangles) {
    for (int k = 0; k < 3; ++k) {
      edges.emplace_back(std::min(t[k], t[(k + 1) % 3]), std::max(t[k], t[(k + 1) % 3]));
    }
  }
  std::sort(edges.begin(), edges.end());
  std::vector<bool> on(mesh.vertices.size(), false);
  for (size_t i = 0; i < edges.size();) {
    size_t j = i;
    while (j < edges.size() && edges[j] == edges[i]) ++j;
    if (j - i == 1) on[edges[i].first] = on[edges[i].second] = true;
    i = j;
  }
  return on;
}

// Smallest interior angle over all triangles, degrees.
inline double min_angle_deg(const SurfaceMesh& mesh) {
  double worst = 180.0;
  for (const auto& t : mesh.triangles) {
    for (int k = 0; k < 3; ++k) {
      const Vec3 u = mesh.vertices[t[(k + 1) % 3]] - mesh.vertices[t[k]];
      const Vec3 v = mesh.vertices[t[(k + 2) % 3]] - mesh.vertices[t[k]];
      const double angle = std::acos(std::clamp(u.normalized().dot(v.normalized()), -1.0, 1.0));
      worst = std::min(worst, angle * 180.0 / std::numbers::pi);
    }
  }
  return worst;
}

inline double projected_radius(const Vec3& v) {
  return std::hypot(v.x(), v.y());
}

}  // namespace phaco::test
