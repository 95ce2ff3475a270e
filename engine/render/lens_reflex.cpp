#include "engine/render/lens_reflex.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>

namespace phaco::render {
namespace {

bool is_lens(const BodyView& b) {
  return b.look == Look::LensSurface || b.look == Look::LensInterior;
}

// The top surface's normal at cell (c, r): the slope of its heights two cells either side,
// weighted 1 2 1 across (a missing neighbour counts as level with the cell). So a step as sharp as
// a trench's rim tilts the normal over a band ~0.3 mm wide, a few pixels at the trainer's zoom:
// the wall facing the illuminator reads lighter, the one facing away darker, as a groove does.
std::array<float, 4> texel(const ThicknessMap& m, int c, int r) {
  constexpr int kReach = 2;
  const int n = m.size;
  const float h0 = m.top_z[static_cast<size_t>(r) * n + c];
  if (h0 == kNoSurface) return {m.mm[static_cast<size_t>(r) * n + c], 0, 0, 0};
  auto h = [&](int dc, int dr) {
    const int cc = std::clamp(c + dc, 0, n - 1), rr = std::clamp(r + dr, 0, n - 1);
    const float v = m.top_z[static_cast<size_t>(rr) * n + cc];
    return v == kNoSurface ? h0 : v;
  };
  float hx = 0, hy = 0;
  for (int k = -1; k <= 1; ++k) {
    const float w = k == 0 ? 0.5f : 0.25f;
    hx += w * (h(kReach, k) - h(-kReach, k));
    hy += w * (h(k, kReach) - h(k, -kReach));
  }
  hx /= 2 * kReach * m.cell_mm;
  hy /= 2 * kReach * m.cell_mm;
  const float len = std::sqrt(hx * hx + hy * hy + 1);
  return {m.mm[static_cast<size_t>(r) * n + c], -hx / len, -hy / len, 1};
}

}  // namespace

LensReflexMap::LensReflexMap() {
  map_.size = 1;
  const float none[4] = {0, 0, 0, 0};
  // The fundus disc: a centre and a ring, as one fan, its normal +z; positions come with the map.
  const std::vector<float> up = [] {
    std::vector<float> n(3 * (kFundusSegments + 2), 0.0f);
    for (size_t i = 2; i < n.size(); i += 3) n[i] = 1;
    return n;
  }();
  glGenBuffers(1, &fundus_normals_);
  glBindBuffer(GL_ARRAY_BUFFER, fundus_normals_);
  glBufferData(GL_ARRAY_BUFFER, up.size() * sizeof(float), up.data(), GL_STATIC_DRAW);
  for (Slot& slot : slots_) {
    glGenTextures(1, &slot.texture);
    glBindTexture(GL_TEXTURE_2D, slot.texture);
    glTexImage2D(GL_TEXTURE_2D, 0, GL_RGBA32F, 1, 1, 0, GL_RGBA, GL_FLOAT, none);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_LINEAR);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
    glGenVertexArrays(1, &slot.fundus_vao);
    glGenBuffers(1, &slot.fundus_positions);
    glBindVertexArray(slot.fundus_vao);
    glBindBuffer(GL_ARRAY_BUFFER, slot.fundus_positions);
    glBufferData(GL_ARRAY_BUFFER, 3 * (kFundusSegments + 2) * sizeof(float), nullptr,
                 GL_DYNAMIC_DRAW);
    glVertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, 0, nullptr);
    glEnableVertexAttribArray(0);
    glBindBuffer(GL_ARRAY_BUFFER, fundus_normals_);
    glVertexAttribPointer(1, 3, GL_FLOAT, GL_FALSE, 0, nullptr);
    glEnableVertexAttribArray(1);
    glBindVertexArray(0);
  }
}

LensReflexMap::~LensReflexMap() {
  for (Slot& slot : slots_) {
    glDeleteTextures(1, &slot.texture);
    glDeleteVertexArrays(1, &slot.fundus_vao);
    glDeleteBuffers(1, &slot.fundus_positions);
  }
  glDeleteBuffers(1, &fundus_normals_);
}

bool LensReflexMap::changed(const RenderSnapshot& s) {
  lens_.clear();
  for (const BodyView& b : s.bodies)
    if (is_lens(b)) lens_.push_back(&b);
  bool same = lens_.size() == built_versions_.size();
  for (size_t i = 0; same && i < lens_.size(); ++i)
    same = lens_[i]->topology_version == built_versions_[i] &&
           lens_[i]->xyz.size() == built_xyz_[i].size() &&
           std::memcmp(lens_[i]->xyz.data(), built_xyz_[i].data(),
                       lens_[i]->xyz.size() * sizeof(float)) == 0;
  if (same) return false;
  built_versions_.resize(lens_.size());
  built_xyz_.resize(lens_.size());
  for (size_t i = 0; i < lens_.size(); ++i) {
    built_versions_[i] = lens_[i]->topology_version;
    built_xyz_[i].assign(lens_[i]->xyz.begin(), lens_[i]->xyz.end());
  }
  return true;
}

void LensReflexMap::update(const RenderSnapshot& s, FrameStats& stats) {
  if (!changed(s)) return;
  build_thickness_map(lens_, kSize, map_);
  const int n = map_.size;
  texels_.resize(static_cast<size_t>(n) * n);
  for (int r = 0; r < n; ++r)
    for (int c = 0; c < n; ++c) texels_[static_cast<size_t>(r) * n + c] = texel(map_, c, r);
  // Into the slot the last frame did not draw with: writing a texture or buffer that frame may
  // still be reading can make the driver finish that frame first. (Measured with one slot, a lens
  // changing every frame drew 7–17 ms slower than a still one at 1280×720; with two, 0–8 ms: at
  // load average 8, so these are rough.)
  current_ = 1 - current_;
  Slot& slot = slots_[current_];
  glBindTexture(GL_TEXTURE_2D, slot.texture);
  glPixelStorei(GL_UNPACK_ALIGNMENT, 4);
  if (n != slot.size) {
    glTexImage2D(GL_TEXTURE_2D, 0, GL_RGBA32F, n, n, 0, GL_RGBA, GL_FLOAT, texels_.data());
    slot.size = n;
  } else {
    glTexSubImage2D(GL_TEXTURE_2D, 0, 0, 0, n, n, GL_RGBA, GL_FLOAT, texels_.data());
  }
  ++stats.uploads;

  has_lens_ = !lens_.empty();
  const float span = map_.cell_mm * static_cast<float>(n);
  const float cx = map_.origin_x + span / 2, cy = map_.origin_y + span / 2;
  const float radius = span / 2 - 2 * map_.cell_mm, z = map_.bottom_z - 0.05f;
  float disc[3 * (kFundusSegments + 2)] = {cx, cy, z};
  for (int i = 0; i <= kFundusSegments; ++i) {
    const float a = 6.2831853f * static_cast<float>(i) / kFundusSegments;
    disc[3 * (i + 1)] = cx + radius * std::cos(a);
    disc[3 * (i + 1) + 1] = cy + radius * std::sin(a);
    disc[3 * (i + 1) + 2] = z;
  }
  glBindBuffer(GL_ARRAY_BUFFER, slot.fundus_positions);
  glBufferSubData(GL_ARRAY_BUFFER, 0, sizeof disc, disc);
}

void LensReflexMap::draw_fundus(GLuint program, FrameStats& stats) const {
  if (!has_lens_) return;
  glUseProgram(program);
  glUniform1f(glGetUniformLocation(program, "u_reflex_mu"), 0.0f);
  glBindVertexArray(slots_[current_].fundus_vao);
  glDrawArrays(GL_TRIANGLE_FAN, 0, kFundusSegments + 2);
  stats.triangles += kFundusSegments;
  ++stats.draw_calls;
}

void LensReflexMap::bind(GLuint program, int unit) const {
  glUseProgram(program);
  glActiveTexture(GL_TEXTURE0 + unit);
  glBindTexture(GL_TEXTURE_2D, slots_[current_].texture);
  glActiveTexture(GL_TEXTURE0);
  glUniform1i(glGetUniformLocation(program, "u_lens_map"), unit);
  glUniform2f(glGetUniformLocation(program, "u_lens_map_origin"), map_.origin_x, map_.origin_y);
  glUniform1f(glGetUniformLocation(program, "u_lens_map_span"),
              map_.cell_mm * static_cast<float>(map_.size));
}

}  // namespace phaco::render
