// Procedural instruments and textures; see procedural.hpp.
#include "engine/render/procedural.hpp"

#include <algorithm>
#include <cmath>

#include "engine/core/math.hpp"
#include "engine/io/tool_shape.hpp"

namespace phaco::render {
namespace {

constexpr float kPi = 3.14159265358979f;

void add_vertex(ToolMesh& m, const Vec3f& p, const Vec3f& n) {
  m.xyz.insert(m.xyz.end(), {p.x(), p.y(), p.z()});
  m.normal.insert(m.normal.end(), {n.x(), n.y(), n.z()});
}

uint32_t vertex_count(const ToolMesh& m) {
  return static_cast<uint32_t>(m.xyz.size() / 3);
}

// Two unit vectors perpendicular to axis.
void basis(const Vec3f& axis, Vec3f& u, Vec3f& w) {
  const Vec3f helper = std::abs(axis.x()) < 0.9f ? Vec3f::UnitX() : Vec3f::UnitY();
  u = axis.cross(helper).normalized();
  w = axis.cross(u);
}

// A tube (truncated cone) from a (radius ra) to b (radius rb), closed by flat caps.
void add_tube(ToolMesh& m, const Vec3f& a, const Vec3f& b, float ra, float rb, int segments = 14) {
  const Vec3f axis = (b - a).normalized();
  Vec3f u, w;
  basis(axis, u, w);
  const uint32_t base = vertex_count(m);
  for (int i = 0; i < segments; ++i) {
    const float t = 2 * kPi * i / segments;
    const Vec3f radial = std::cos(t) * u + std::sin(t) * w;
    add_vertex(m, a + ra * radial, radial);
    add_vertex(m, b + rb * radial, radial);
  }
  for (int i = 0; i < segments; ++i) {
    const uint32_t i0 = base + 2 * i, i1 = base + 2 * ((i + 1) % segments);
    m.tris.insert(m.tris.end(), {i0, i1, i0 + 1, i0 + 1, i1, i1 + 1});
  }
  for (int end = 0; end < 2; ++end) {
    const Vec3f c = end ? b : a;
    const float r = end ? rb : ra;
    const Vec3f n = end ? axis : Vec3f(-axis);
    const uint32_t centre = vertex_count(m);
    add_vertex(m, c, n);
    for (int i = 0; i < segments; ++i) {
      const float t = 2 * kPi * i / segments;
      add_vertex(m, c + r * (std::cos(t) * u + std::sin(t) * w), n);
    }
    for (int i = 0; i < segments; ++i) {
      const uint32_t p = centre + 1 + i, q = centre + 1 + (i + 1) % segments;
      if (end)
        m.tris.insert(m.tris.end(), {centre, p, q});
      else
        m.tris.insert(m.tris.end(), {centre, q, p});
    }
  }
}

void add_sphere(ToolMesh& m, const Vec3f& c, float r, int rings = 8, int segments = 14) {
  const uint32_t base = vertex_count(m);
  for (int i = 0; i <= rings; ++i) {
    const float phi = kPi * i / rings;
    for (int j = 0; j <= segments; ++j) {
      const float t = 2 * kPi * j / segments;
      const Vec3f n(std::sin(phi) * std::cos(t), std::sin(phi) * std::sin(t), std::cos(phi));
      add_vertex(m, c + r * n, n);
    }
  }
  const uint32_t row = segments + 1;
  for (int i = 0; i < rings; ++i)
    for (int j = 0; j < segments; ++j) {
      const uint32_t a = base + i * row + j, b = a + row;
      m.tris.insert(m.tris.end(), {a, b, a + 1, a + 1, b, b + 1});
    }
}

// A flat plate in the instrument's x-z plane, thickness along y: outline is convex, (x, z) pairs
// in order. Flat-shaded (each face its own vertices).
void add_plate(ToolMesh& m, const std::vector<std::array<float, 2>>& outline, float thickness) {
  const float h = thickness / 2;
  const size_t n = outline.size();
  for (int side = 0; side < 2; ++side) {
    const float y = side ? h : -h;
    const Vec3f normal(0, side ? 1.0f : -1.0f, 0);
    const uint32_t base = vertex_count(m);
    for (const auto& p : outline) add_vertex(m, Vec3f(p[0], y, p[1]), normal);
    for (uint32_t i = 1; i + 1 < n; ++i) {
      if (side)
        m.tris.insert(m.tris.end(), {base, base + i + 1, base + i});
      else
        m.tris.insert(m.tris.end(), {base, base + i, base + i + 1});
    }
  }
  for (size_t i = 0; i < n; ++i) {
    const auto& p = outline[i];
    const auto& q = outline[(i + 1) % n];
    const Vec3f a(p[0], 0, p[1]), b(q[0], 0, q[1]);
    const Vec3f normal = (b - a).cross(Vec3f::UnitY()).normalized();
    const uint32_t base = vertex_count(m);
    add_vertex(m, a + Vec3f(0, -h, 0), normal);
    add_vertex(m, b + Vec3f(0, -h, 0), normal);
    add_vertex(m, b + Vec3f(0, h, 0), normal);
    add_vertex(m, a + Vec3f(0, h, 0), normal);
    m.tris.insert(m.tris.end(), {base, base + 1, base + 2, base, base + 2, base + 3});
  }
}

// Deterministic pseudo-random numbers for the textures (the same image every run).
struct Lcg {
  uint32_t state;
  float next() {
    state = state * 1664525u + 1013904223u;
    return static_cast<float>(state >> 8) / static_cast<float>(1u << 24);
  }
};

}  // namespace

ToolMeshes make_tool_mesh(ToolKind kind) {
  ToolMeshes t;
  const float L = kShaftLength;
  switch (kind) {
    case ToolKind::Forceps:
      // Utrata-style: a round shaft ending at the pivot, two long jaws with bent teeth.
      add_tube(t.body, Vec3f(0, 0, kForcepsJawLength), Vec3f(0, 0, L), 0.35f, 0.45f);
      add_tube(t.jaw, Vec3f(0, 0, 0.25f), Vec3f(0, 0, kForcepsJawLength), 0.12f, 0.22f, 10);
      add_tube(t.jaw, Vec3f(0, 0.25f, 0.05f), Vec3f(0, 0, 0.3f), 0.07f, 0.11f, 8);
      break;
    case ToolKind::Keratome: {
      // Angled blade, 2.4 mm at its shoulders, then a neck and the handle shaft.
      add_plate(t.body,
                {{0.0f, 0.0f},
                 {1.2f, 2.2f},
                 {1.2f, 3.2f},
                 {0.35f, 4.2f},
                 {-0.35f, 4.2f},
                 {-1.2f, 3.2f},
                 {-1.2f, 2.2f}},
                0.12f);
      add_tube(t.body, Vec3f(0, 0, 4.0f), Vec3f(0, 0, L), 0.3f, 0.6f);
      break;
    }
    case ToolKind::Cystotome: {
      // 27 G needle with its point bent at a right angle; the shaft's axis is where
      // engine/io/tool_shape says, which the ports hold.
      const Vec3f bend = shaft_offset_local(kind).cast<float>();
      add_tube(t.body, Vec3f(0, 0, 0), bend, 0.05f, 0.2f, 10);
      add_sphere(t.body, bend, 0.2f);
      add_tube(t.body, bend, bend + Vec3f(0, 0, L), 0.2f, 0.2f);
      break;
    }
    case ToolKind::PhacoProbe:
      // The 0.9 mm titanium tip, then the wider irrigation sleeve.
      add_tube(t.body, Vec3f(0, 0, 0), Vec3f(0, 0, kPhacoTipLength + 0.2f), 0.45f, 0.45f);
      add_tube(t.body, Vec3f(0, 0, kPhacoTipLength), Vec3f(0, 0, L), 0.65f, 0.9f);
      break;
    case ToolKind::Hook:
    case ToolKind::Chopper: {
      // Chopper / Sinskey hook: a bent end on a thin shaft (the nucleus_removal drill's second
      // instrument, issue 19); the bend is engine/io/tool_shape's, as for the cystotome.
      const Vec3f bend = shaft_offset_local(kind).cast<float>();
      add_tube(t.body, Vec3f(0, 0, 0), bend, 0.12f, 0.16f, 10);
      add_sphere(t.body, bend, 0.17f);
      add_tube(t.body, bend, bend + Vec3f(0, 0, L), 0.17f, 0.4f);
      break;
    }
    case ToolKind::Aspirator:
      // Irrigation/aspiration tip: closed round end.
      add_sphere(t.body, Vec3f(0, 0, 0.45f), 0.45f);
      add_tube(t.body, Vec3f(0, 0, 0.45f), Vec3f(0, 0, L), 0.45f, 0.8f);
      break;
  }
  return t;
}

TextureImage make_iris_texture(bool blue) {
  TextureImage img;
  img.width = 512;
  img.height = 128;
  img.rgb.resize(static_cast<size_t>(img.width) * img.height * 3);
  Lcg rng{12345u};
  // Radial stroma fibres: a sum of sines in angle with random phases, slowly drifting with v.
  constexpr int kWaves = 24;
  float freq[kWaves], phase[kWaves], drift[kWaves];
  for (int k = 0; k < kWaves; ++k) {
    freq[k] = std::round(8 + rng.next() * 120);
    phase[k] = rng.next() * 2 * kPi;
    drift[k] = (rng.next() - 0.5f) * 4;
  }
  const Vec3f base = blue ? Vec3f(0.30f, 0.42f, 0.56f) : Vec3f(0.36f, 0.21f, 0.10f);
  const Vec3f light = blue ? Vec3f(0.62f, 0.72f, 0.80f) : Vec3f(0.62f, 0.42f, 0.20f);
  for (int y = 0; y < img.height; ++y) {
    const float v = (y + 0.5f) / img.height;
    for (int x = 0; x < img.width; ++x) {
      const float u = (x + 0.5f) / img.width;
      float fibre = 0;
      for (int k = 0; k < kWaves; ++k)
        fibre += std::sin(2 * kPi * freq[k] * u + phase[k] + drift[k] * v);
      fibre = 0.5f + 0.5f * std::tanh(fibre / 3);
      // Collarette (a lighter ring a third of the way out), dark pupillary ruff and limbal ring.
      const float collarette = std::exp(-std::pow((v - 0.33f) / 0.06f, 2.0f));
      const float ruff = v < 0.05f ? 0.45f : 1.0f;
      const float root = 1.0f - 0.45f * std::clamp((v - 0.85f) / 0.15f, 0.0f, 1.0f);
      Vec3f c = base + (light - base) * (0.55f * fibre + 0.5f * collarette);
      c *= ruff * root;
      uint8_t* px = &img.rgb[(static_cast<size_t>(y) * img.width + x) * 3];
      for (int ch = 0; ch < 3; ++ch)
        px[ch] = static_cast<uint8_t>(std::clamp(c[ch], 0.0f, 1.0f) * 255 + 0.5f);
    }
  }
  return img;
}

namespace {

// Bilinear lookup of a polar image, u wrapping, v clamped.
void sample_polar(const TextureImage& polar, double u, double v, uint8_t* out) {
  const double x = u * polar.width - 0.5, y = std::clamp(v, 0.0, 1.0) * (polar.height - 1);
  const int x0 = static_cast<int>(std::floor(x)), y0 = static_cast<int>(std::floor(y));
  const double fx = x - x0, fy = y - y0;
  for (int c = 0; c < 3; ++c) {
    double acc = 0;
    for (int dy = 0; dy < 2; ++dy)
      for (int dx = 0; dx < 2; ++dx) {
        const int xx = ((x0 + dx) % polar.width + polar.width) % polar.width;
        const int yy = std::min(y0 + dy, polar.height - 1);
        const double w = (dx ? fx : 1 - fx) * (dy ? fy : 1 - fy);
        acc += w * polar.rgb[(static_cast<size_t>(yy) * polar.width + xx) * 3 + c];
      }
    out[c] = static_cast<uint8_t>(std::clamp(acc + 0.5, 0.0, 255.0));
  }
}

// Resamples a polar image onto a size × size square over [−1, 1]²; v_of(ρ) maps the radius.
template <class VOf>
TextureImage polar_to_square(const TextureImage& polar, int size, VOf v_of) {
  TextureImage img;
  img.width = img.height = size;
  img.rgb.resize(static_cast<size_t>(size) * size * 3);
  for (int y = 0; y < size; ++y)
    for (int x = 0; x < size; ++x) {
      const double px = (x + 0.5) / size * 2 - 1, py = (y + 0.5) / size * 2 - 1;
      const double u = std::atan2(py, px) / (2 * kPi) + 0.5;
      sample_polar(polar, u, v_of(std::hypot(px, py)),
                   &img.rgb[(static_cast<size_t>(y) * size + x) * 3]);
    }
  return img;
}

}  // namespace

TextureImage bake_iris_disc(const TextureImage& polar, double pupil_ratio, int size) {
  const double p = std::clamp(pupil_ratio, 0.0, 0.95);
  return polar_to_square(polar, size, [p](double rho) { return (rho - p) / (1 - p); });
}

TextureImage make_sclera_texture() {
  TextureImage img;
  img.width = 1024;
  img.height = 256;
  img.rgb.resize(static_cast<size_t>(img.width) * img.height * 3);
  std::vector<float> vessel(static_cast<size_t>(img.width) * img.height, 0.0f);
  Lcg rng{777u};
  // Conjunctival and episcleral vessels: random walks from the periphery (v = 1) toward the
  // limbus, thinning as they go, some branching.
  auto stamp = [&](float x, float y, float r, float strength) {
    const int r_px = static_cast<int>(std::ceil(r)) + 1;
    for (int dy = -r_px; dy <= r_px; ++dy)
      for (int dx = -r_px; dx <= r_px; ++dx) {
        const int yy = static_cast<int>(y) + dy;
        if (yy < 0 || yy >= img.height) continue;
        const int xx = ((static_cast<int>(x) + dx) % img.width + img.width) % img.width;
        const float d = std::hypot(static_cast<float>(dx), static_cast<float>(dy));
        const float a = strength * std::clamp(r + 0.5f - d, 0.0f, 1.0f);
        float& cell = vessel[static_cast<size_t>(yy) * img.width + xx];
        cell = std::max(cell, a);
      }
  };
  struct Walker {
    float x, y, dir, r, strength;
  };
  std::vector<Walker> walkers;
  for (int i = 0; i < 45; ++i)
    walkers.push_back({rng.next() * img.width, static_cast<float>(img.height - 1), 0.0f,
                       1.0f + 1.8f * rng.next(), 0.3f + 0.4f * rng.next()});
  while (!walkers.empty()) {
    Walker w = walkers.back();
    walkers.pop_back();
    while (w.y > img.height * 0.08f && w.r > 0.35f) {
      stamp(w.x, w.y, w.r, w.strength);
      w.dir = std::clamp(w.dir + (rng.next() - 0.5f) * 0.5f, -1.2f, 1.2f);
      w.x += std::sin(w.dir) * 1.5f;
      w.y -= std::cos(w.dir) * 1.0f;
      w.r *= 0.994f;
      if (rng.next() < 0.012f && walkers.size() < 400)
        walkers.push_back(
            {w.x, w.y, w.dir + (rng.next() < 0.5f ? -0.8f : 0.8f), w.r * 0.7f, w.strength * 0.8f});
    }
  }
  const Vec3f white(0.93f, 0.91f, 0.88f), red(0.72f, 0.22f, 0.20f);
  for (int y = 0; y < img.height; ++y)
    for (int x = 0; x < img.width; ++x) {
      const float a = vessel[static_cast<size_t>(y) * img.width + x];
      const Vec3f c = white + (red - white) * a;
      uint8_t* px = &img.rgb[(static_cast<size_t>(y) * img.width + x) * 3];
      for (int ch = 0; ch < 3; ++ch)
        px[ch] = static_cast<uint8_t>(std::clamp(c[ch], 0.0f, 1.0f) * 255 + 0.5f);
    }
  // Polar angle from the front axis: ρ = sin φ on the unit sphere seen from +z.
  return polar_to_square(img, 1024,
                         [](double rho) { return std::asin(std::min(rho, 1.0)) / (kPi / 2); });
}

}  // namespace phaco::render
