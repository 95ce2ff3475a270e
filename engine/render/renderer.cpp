// Over 600 lines on purpose: the five passes share one GL state, buffers and shaders (Impl).
// Split, they would share Renderer::Impl (one set of buffers per body slot, the shaders) through a
// second, internal header for no gain.
// The microscope view (renderer.hpp). Per view (one, or two for side-by-side stereo) the passes
// are:
//   1. opaque tissue: sclera, iris, lens surface (red reflex dimmed by the lens's thickness map,
//      lens_reflex.hpp), exposed nucleus, the fundus's glow behind the lens
//   2. instruments (opaque steel)
//   3. instrument shadows projected along the illuminator onto lens/iris, once per pixel (stencil)
//   4. translucent membranes: capsule (pulled forward by a polygon offset: it lies on the lens),
//      its cut edges as ribbons, then the cornea (front faces only)
//   5. overlays without depth test: guidance cues and contact rings
// Before them, panels that will cover parts of the window are written to the depth buffer at the
// near plane, so no pass shades what they hide.
// Buffers are kept per body slot and grow only when a count grows; index buffers are re-sent only
// when a body's topology_version changes; positions and normals are re-sent every frame.
#include "engine/render/renderer.hpp"

#include <epoxy/gl.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <numbers>
#include <string>
#include <utility>

#include "engine/render/lens_reflex.hpp"
#include "engine/render/procedural.hpp"
#include "engine/render/shaders.hpp"

namespace phaco::render {
namespace {

using Mat4f = Eigen::Matrix4f;

// Illuminator: coaxial, tilted 20° toward 12 o'clock, so a shadow slides away from its instrument
// by tan 20° ≈ 0.36 × the height above the tissue — the depth cue.
const Vec3 kToLight =
    Vec3(0.0, std::sin(20.0 * std::numbers::pi / 180), std::cos(20.0 * std::numbers::pi / 180));

GLuint compile(GLenum type, const char* source, const char* name) {
  const GLuint shader = glCreateShader(type);
  glShaderSource(shader, 1, &source, nullptr);
  glCompileShader(shader);
  GLint ok = 0;
  glGetShaderiv(shader, GL_COMPILE_STATUS, &ok);
  if (!ok) {
    char log[4096] = {};
    glGetShaderInfoLog(shader, sizeof log, nullptr, log);
    glDeleteShader(shader);
    throw RenderError(std::string("renderer: shader '") + name + "' does not compile: " + log);
  }
  return shader;
}

GLuint link(const char* vertex, const char* fragment, const char* name) {
  const GLuint vs = compile(GL_VERTEX_SHADER, vertex, name);
  const GLuint fs = compile(GL_FRAGMENT_SHADER, fragment, name);
  const GLuint program = glCreateProgram();
  glAttachShader(program, vs);
  glAttachShader(program, fs);
  glLinkProgram(program);
  glDeleteShader(vs);
  glDeleteShader(fs);
  GLint ok = 0;
  glGetProgramiv(program, GL_LINK_STATUS, &ok);
  if (!ok) {
    char log[4096] = {};
    glGetProgramInfoLog(program, sizeof log, nullptr, log);
    glDeleteProgram(program);
    throw RenderError(std::string("renderer: program '") + name + "' does not link: " + log);
  }
  return program;
}

Mat4f perspective(double fovy, double aspect, double near, double far) {
  const double f = 1.0 / std::tan(fovy / 2);
  Mat4f m = Mat4f::Zero();
  m(0, 0) = static_cast<float>(f / aspect);
  m(1, 1) = static_cast<float>(f);
  m(2, 2) = static_cast<float>((far + near) / (near - far));
  m(2, 3) = static_cast<float>(2 * far * near / (near - far));
  m(3, 2) = -1;
  return m;
}

Mat4f look_at(const Vec3& eye, const Vec3& target, const Vec3& up) {
  const Vec3 f = (target - eye).normalized();
  const Vec3 s = f.cross(up).normalized();
  const Vec3 u = s.cross(f);
  Mat4f m = Mat4f::Identity();
  m.block<1, 3>(0, 0) = s.cast<float>().transpose();
  m.block<1, 3>(1, 0) = u.cast<float>().transpose();
  m.block<1, 3>(2, 0) = -f.cast<float>().transpose();
  m(0, 3) = static_cast<float>(-s.dot(eye));
  m(1, 3) = static_cast<float>(-u.dot(eye));
  m(2, 3) = static_cast<float>(f.dot(eye));
  return m;
}

struct Camera {
  Mat4f view_proj;
  Vec3 eye;
};

// eye_offset_x: the stereo eye's offset along +x at the objective (0 for mono). Both eyes look at
// the focal point on the axis (the microscope's convergent stereo).
Camera make_camera(const Microscope& m, double eye_offset_x, int width, int height) {
  const double aspect = static_cast<double>(width) / std::max(height, 1);
  const double half_field = m.field_mm / 2;
  // The field spans the shorter side of the viewport.
  const double tan_half_y = aspect >= 1 ? half_field / m.working_distance_mm
                                        : half_field / m.working_distance_mm / aspect;
  const Vec3 target(m.centre_mm.x(), m.centre_mm.y(), m.focus_z_mm);
  const Vec3 eye = target + Vec3(eye_offset_x, 0, m.working_distance_mm);
  // The eye spans about 30 mm in depth; keep near/far snug for depth precision.
  const double near = std::max(m.working_distance_mm - 40.0, 1.0);
  const double far = m.working_distance_mm + 60.0;
  return {perspective(2 * std::atan(tan_half_y), aspect, near, far) *
              look_at(eye, target, Vec3::UnitY()),
          eye};
}

Mat4f to_mat4(const Eigen::Affine3d& a) {
  return a.matrix().cast<float>();
}

void set_mat4(GLuint program, const char* name, const Mat4f& m) {
  glUniformMatrix4fv(glGetUniformLocation(program, name), 1, GL_FALSE, m.data());
}
void set_float(GLuint program, const char* name, double v) {
  glUniform1f(glGetUniformLocation(program, name), static_cast<float>(v));
}
void set_vec3(GLuint program, const char* name, const Vec3& v) {
  glUniform3f(glGetUniformLocation(program, name), static_cast<float>(v.x()),
              static_cast<float>(v.y()), static_cast<float>(v.z()));
}

}  // namespace

struct Renderer::Impl {
  struct BodySlot {
    GLuint vao = 0, positions = 0, normals = 0, indices = 0, pieces = 0;
    size_t piece_capacity = 0;   // bytes the piece buffer holds
    size_t vertex_capacity = 0;  // floats the vertex buffers hold
    size_t index_capacity = 0;   // indices the index buffer holds
    uint32_t index_count = 0;
    uint64_t topology_version = std::numeric_limits<uint64_t>::max();
    std::vector<float> normal;  // per-vertex normals, recomputed each frame (grows only)
  };
  struct ToolSlot {
    GLuint vao = 0, buffers[3] = {};
    uint32_t index_count = 0;
  };
  struct OverlayVertex {
    float x, y, z, r, g, b, a;
  };

  GLuint body_programs[shaders::kLookCount] = {};  // one per look (shaders.hpp)
  GLuint shadow_program = 0, overlay_program = 0;
  GLuint iris_texture = 0, sclera_texture = 0;
  TextureImage iris_polar[2];  // brown, blue
  int iris_baked_colour = -1;  // which polar image iris_texture holds, at which pupil ratio
  double iris_baked_ratio = -1;
  std::vector<BodySlot> bodies;
  std::unique_ptr<LensReflexMap> lens_map;  // the lens looks' thickness map (lens_reflex.hpp)
  // One per ToolKind, the chopper (the last) included: with six, the chopper was drawn from
  // past the array's end (the forceps' jaw, straight, where its bent point should be).
  static constexpr int kToolKinds = static_cast<int>(ToolKind::Chopper) + 1;
  ToolSlot tool_bodies[kToolKinds], tool_jaw;
  GLuint overlay_vao = 0, overlay_vbo = 0;
  size_t overlay_capacity = 0;  // vertices
  GLuint cover_vao = 0, cover_vbo = 0;
  size_t cover_bytes = 0;
  std::vector<float> cover_xyz;  // the covered rectangles' triangles, clip space
  std::vector<OverlayVertex> overlay;
  std::vector<uint32_t> sclera_tris;  // scratch of sclera_outside()
  size_t edges_end = 0;  // overlay[0, edges_end): cut edges (depth tested); the rest on top

  // Eye dimensions read from the bodies (the renderer has no EyeParams): refreshed whenever a
  // body's topology changes. Defaults are the standard eye (DESIGN.md §6).
  double globe_centre_z = -6.17, globe_r = 12.0, limbus_r = 5.8;
  double pupil_r = 3.75, iris_outer_r = 5.6, iris_z = 1.8, lens_a = 4.7, lens_c = 1.8;

  static void upload(GLenum target, GLuint buffer, const void* data, size_t bytes,
                     size_t& capacity_bytes, FrameStats& stats) {
    glBindBuffer(target, buffer);
    if (bytes > capacity_bytes) {
      glBufferData(target, static_cast<GLsizeiptr>(bytes), data, GL_DYNAMIC_DRAW);
      capacity_bytes = bytes;
    } else if (bytes > 0) {
      glBufferSubData(target, 0, static_cast<GLsizeiptr>(bytes), data);
    }
    ++stats.uploads;
  }

  void make_tool(ToolSlot& slot, const ToolMesh& mesh) {
    glGenVertexArrays(1, &slot.vao);
    glGenBuffers(3, slot.buffers);
    glBindVertexArray(slot.vao);
    glBindBuffer(GL_ARRAY_BUFFER, slot.buffers[0]);
    glBufferData(GL_ARRAY_BUFFER, mesh.xyz.size() * sizeof(float), mesh.xyz.data(), GL_STATIC_DRAW);
    glVertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, 0, nullptr);
    glEnableVertexAttribArray(0);
    glBindBuffer(GL_ARRAY_BUFFER, slot.buffers[1]);
    glBufferData(GL_ARRAY_BUFFER, mesh.normal.size() * sizeof(float), mesh.normal.data(),
                 GL_STATIC_DRAW);
    glVertexAttribPointer(1, 3, GL_FLOAT, GL_FALSE, 0, nullptr);
    glEnableVertexAttribArray(1);
    glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, slot.buffers[2]);
    glBufferData(GL_ELEMENT_ARRAY_BUFFER, mesh.tris.size() * sizeof(uint32_t), mesh.tris.data(),
                 GL_STATIC_DRAW);
    slot.index_count = static_cast<uint32_t>(mesh.tris.size());
    glBindVertexArray(0);
  }

  static GLuint make_texture(const TextureImage& img, GLuint tex = 0) {
    if (tex == 0) glGenTextures(1, &tex);
    glBindTexture(GL_TEXTURE_2D, tex);
    glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
    glTexImage2D(GL_TEXTURE_2D, 0, GL_RGB8, img.width, img.height, 0, GL_RGB, GL_UNSIGNED_BYTE,
                 img.rgb.data());
    glGenerateMipmap(GL_TEXTURE_2D);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_LINEAR_MIPMAP_NEAREST);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
    return tex;
  }

  // Eye dimensions from the bodies, in their own (unrotated) frame.
  void measure_eye(const RenderSnapshot& s) {
    for (const BodyView& b : s.bodies) {
      const size_t n = b.xyz.size() / 3;
      if (n == 0) continue;
      double r_min = 1e30, r_max = 0, z_max = -1e30, z_sum = 0;
      Vec3 sum = Vec3::Zero();
      for (size_t i = 0; i < n; ++i) {
        const Vec3 p(b.xyz[3 * i], b.xyz[3 * i + 1], b.xyz[3 * i + 2]);
        const double r = std::hypot(p.x(), p.y());
        r_min = std::min(r_min, r);
        r_max = std::max(r_max, r);
        z_max = std::max(z_max, p.z());
        z_sum += p.z();
        sum += p;
      }
      switch (b.look) {
        case Look::Sclera:
          globe_centre_z = sum.z() / static_cast<double>(n);
          globe_r = r_max;
          break;
        case Look::Cornea:
          limbus_r = r_max;
          break;
        case Look::Iris:
          pupil_r = r_min;
          iris_outer_r = r_max;
          iris_z = z_sum / static_cast<double>(n);
          break;
        case Look::LensSurface:
          lens_a = r_max;
          lens_c = z_max;
          break;
        default:
          break;
      }
    }
  }

  void compute_normals(const BodyView& b, std::vector<float>& normal) {
    normal.assign(b.xyz.size(), 0.0f);  // no allocation once the capacity is there
    const float* x = b.xyz.data();
    for (size_t t = 0; t + 2 < b.tris.size(); t += 3) {
      const uint32_t i = b.tris[t], j = b.tris[t + 1], k = b.tris[t + 2];
      const Vec3f a(x[3 * i], x[3 * i + 1], x[3 * i + 2]);
      const Vec3f e1 = Vec3f(x[3 * j], x[3 * j + 1], x[3 * j + 2]) - a;
      const Vec3f e2 = Vec3f(x[3 * k], x[3 * k + 1], x[3 * k + 2]) - a;
      const Vec3f n = e1.cross(e2);  // area-weighted
      for (uint32_t v : {i, j, k})
        for (int c = 0; c < 3; ++c) normal[3 * v + c] += n[c];
    }
    for (size_t v = 0; v + 2 < normal.size(); v += 3) {
      const float len = std::sqrt(normal[v] * normal[v] + normal[v + 1] * normal[v + 1] +
                                  normal[v + 2] * normal[v + 2]);
      if (len > 0)
        for (int c = 0; c < 3; ++c) normal[v + c] /= len;
      else
        normal[v + 2] = 1;
    }
  }

  void upload_bodies(const RenderSnapshot& s, FrameStats& stats) {
    bool topology_changed = false;
    while (bodies.size() < s.bodies.size()) {
      BodySlot slot;
      glGenVertexArrays(1, &slot.vao);
      GLuint buffers[4];
      glGenBuffers(4, buffers);
      slot.positions = buffers[0];
      slot.normals = buffers[1];
      slot.indices = buffers[2];
      slot.pieces = buffers[3];
      glBindVertexArray(slot.vao);
      glBindBuffer(GL_ARRAY_BUFFER, slot.positions);
      glVertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, 0, nullptr);
      glEnableVertexAttribArray(0);
      glBindBuffer(GL_ARRAY_BUFFER, slot.normals);
      glVertexAttribPointer(1, 3, GL_FLOAT, GL_FALSE, 0, nullptr);
      glEnableVertexAttribArray(1);
      glBindBuffer(GL_ARRAY_BUFFER, slot.pieces);
      glVertexAttribPointer(2, 1, GL_UNSIGNED_BYTE, GL_FALSE, 0, nullptr);
      glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, slot.indices);
      glBindVertexArray(0);
      bodies.push_back(std::move(slot));
    }
    for (size_t i = 0; i < s.bodies.size(); ++i)
      topology_changed |= s.bodies[i].topology_version != bodies[i].topology_version;
    if (topology_changed) measure_eye(s);
    for (size_t i = 0; i < s.bodies.size(); ++i) {
      const BodyView& b = s.bodies[i];
      BodySlot& slot = bodies[i];
      compute_normals(b, slot.normal);
      size_t bytes = b.xyz.size() * sizeof(float);
      size_t capacity = slot.vertex_capacity * sizeof(float);
      upload(GL_ARRAY_BUFFER, slot.positions, b.xyz.data(), bytes, capacity, stats);
      capacity = slot.vertex_capacity * sizeof(float);
      upload(GL_ARRAY_BUFFER, slot.normals, slot.normal.data(), bytes, capacity, stats);
      slot.vertex_capacity = capacity / sizeof(float);
      // A fragmented lens's pieces (attribute 2; without them, or with a count that is not the
      // vertices', the attribute reads 0).
      glBindVertexArray(slot.vao);
      if (b.piece.empty() || b.piece.size() != b.xyz.size() / 3) {
        glDisableVertexAttribArray(2);
      } else {
        upload(GL_ARRAY_BUFFER, slot.pieces, b.piece.data(), b.piece.size(), slot.piece_capacity,
               stats);
        glEnableVertexAttribArray(2);
      }
      glBindVertexArray(0);
      if (b.topology_version != slot.topology_version) {
        glBindVertexArray(slot.vao);  // the element buffer binding is VAO state
        const std::vector<uint32_t>& tris = b.look == Look::Sclera ? sclera_outside(b) : b.tris;
        size_t index_bytes = slot.index_capacity * sizeof(uint32_t);
        upload(GL_ELEMENT_ARRAY_BUFFER, slot.indices, tris.data(), tris.size() * sizeof(uint32_t),
               index_bytes, stats);
        glBindVertexArray(0);
        slot.index_capacity = index_bytes / sizeof(uint32_t);
        slot.index_count = static_cast<uint32_t>(tris.size());
        slot.topology_version = b.topology_version;
      }
    }
    lens_map->update(s, stats);
  }

  // Inside this radius the globe's front belongs to the cornea and the iris under it; up to the
  // iris root (not the limbus) so no gap opens between the iris and the sclera.
  double sclera_hole_r() const { return std::min(limbus_r, iris_outer_r); }

  // The globe's triangles less those wholly inside the cornea's front cap, which the shader
  // would shade only to discard (a third of the sclera's pixels at the default zoom).
  const std::vector<uint32_t>& sclera_outside(const BodyView& b) {
    sclera_tris.clear();
    auto inside = [&](uint32_t v) {
      const float* p = &b.xyz[3 * v];
      return std::hypot(p[0], p[1]) < sclera_hole_r() && p[2] > globe_centre_z;
    };
    for (size_t t = 0; t + 2 < b.tris.size(); t += 3)
      if (!(inside(b.tris[t]) && inside(b.tris[t + 1]) && inside(b.tris[t + 2])))
        sclera_tris.insert(sclera_tris.end(), b.tris.begin() + t, b.tris.begin() + t + 3);
    return sclera_tris;
  }

  // A flat ribbon from a to b, width w, lying across the view direction (−z).
  void ribbon(const Vec3& a, const Vec3& b, double w, const Eigen::Vector4f& colour) {
    Vec3 side = (b - a).cross(Vec3::UnitZ());
    side = side.norm() > 1e-9 ? side.normalized() * (w / 2) : Vec3(w / 2, 0, 0);
    const Vec3 q[4] = {a - side, a + side, b + side, b - side};
    for (int i : {0, 1, 2, 0, 2, 3})
      overlay.push_back({static_cast<float>(q[i].x()), static_cast<float>(q[i].y()),
                         static_cast<float>(q[i].z()), colour[0], colour[1], colour[2], colour[3]});
  }

  // A circle of radius r about centre in the plane z = const, mapped by `to_world`.
  void circle(const Eigen::Affine3d& to_world, const Vec3& centre, double r, double w,
              const Eigen::Vector4f& colour, int segments = 64) {
    for (int i = 0; i < segments; ++i) {
      const double t0 = 2 * std::numbers::pi * i / segments,
                   t1 = 2 * std::numbers::pi * (i + 1) / segments;
      ribbon(to_world * (centre + r * Vec3(std::cos(t0), std::sin(t0), 0)),
             to_world * (centre + r * Vec3(std::cos(t1), std::sin(t1), 0)), w, colour);
    }
  }

  void build_overlay(const RenderSnapshot& s, const Eigen::Affine3d& eye, double px_mm,
                     bool guidance) {
    overlay.clear();  // keeps its capacity
    // Cut and rim edges of membranes: a bright line a couple of pixels wide.
    const Eigen::Vector4f edge_colour(1.0f, 0.97f, 0.88f, 0.95f);
    for (const BodyView& b : s.bodies)
      for (size_t e = 0; e + 1 < b.edges.size(); e += 2) {
        const uint32_t i = b.edges[e], j = b.edges[e + 1];
        const Vec3 a(b.xyz[3 * i], b.xyz[3 * i + 1], b.xyz[3 * i + 2]);
        const Vec3 c(b.xyz[3 * j], b.xyz[3 * j + 1], b.xyz[3 * j + 2]);
        ribbon(eye * a, eye * c, 2.0 * px_mm, edge_colour);
      }
    edges_end = overlay.size();
    if (guidance) {
      const GuidanceView& g = s.guidance;
      const double w = 2.5 * px_mm;
      const Eigen::Vector4f green(0.25f, 0.95f, 0.35f, 0.85f), yellow(1.0f, 0.85f, 0.2f, 0.9f),
          cyan(0.2f, 0.85f, 1.0f, 0.9f);
      if (g.rhexis_centre_mm && g.rhexis_diameter_mm > 0)
        circle(eye, *g.rhexis_centre_mm, g.rhexis_diameter_mm / 2, w, green, 96);
      for (const auto& [site, colour] :
           {std::pair{g.puncture_site_mm, yellow}, std::pair{g.grasp_site_mm, cyan}}) {
        if (!site) continue;
        circle(eye, *site, 0.3, w, colour, 24);
        ribbon(eye * (*site - Vec3(0.2, 0, 0)), eye * (*site + Vec3(0.2, 0, 0)), w, colour);
        ribbon(eye * (*site - Vec3(0, 0.2, 0)), eye * (*site + Vec3(0, 0.2, 0)), w, colour);
      }
      if (g.trench_centre_mm && g.trench_arm_mm > 0)
        for (int k = 0; k < 2; ++k) {
          const double a = (g.trench_first_angle_deg + 90.0 * k) * std::numbers::pi / 180;
          const Vec3 d = g.trench_arm_mm * Vec3(std::cos(a), std::sin(a), 0);
          ribbon(eye * (*g.trench_centre_mm - d), eye * (*g.trench_centre_mm + d), w, green);
        }
      for (const Vec3& port : g.ports_mm) circle(eye, port, 0.6, w, cyan, 32);
    }
    // Contact rings around instrument tips touching tissue (world frame: instruments do not turn
    // with the globe).
    const Eigen::Vector4f orange(1.0f, 0.5f, 0.1f, 0.9f);
    for (const ToolView& t : s.tools)
      if (t.in_contact) circle(Eigen::Affine3d::Identity(), t.tip_mm, 0.5, 2.0 * px_mm, orange, 32);
  }

  Eigen::Affine3d tool_pose(const ToolView& t) const {
    Eigen::Affine3d m = Eigen::Affine3d::Identity();
    m.translate(t.tip_mm);
    m.rotate(t.quat.normalized());
    return m;
  }

  // Draws every instrument with whichever program is bound (body or shadow).
  void draw_tools(const RenderSnapshot& s, GLuint program, bool shading, FrameStats& stats) {
    for (const ToolView& t : s.tools) {
      const Eigen::Affine3d pose = tool_pose(t);
      const ToolSlot& slot = tool_bodies[static_cast<int>(t.kind)];
      if (shading) {
        const bool phaco = t.kind == ToolKind::PhacoProbe;
        set_float(program, "u_glow", phaco ? std::clamp(t.pedal - 2.0, 0.0, 1.0) : 0.0);
        set_float(program, "u_glow_length", kPhacoTipLength);
        set_vec3(program, "u_tool_colour",
                 t.selected ? Vec3(0.56, 0.62, 0.72) : Vec3(0.50, 0.55, 0.64));
      }
      set_mat4(program, "u_model", to_mat4(pose));
      glBindVertexArray(slot.vao);
      glDrawElements(GL_TRIANGLES, static_cast<GLsizei>(slot.index_count), GL_UNSIGNED_INT,
                     nullptr);
      stats.triangles += slot.index_count / 3;
      ++stats.draw_calls;
      if (t.kind == ToolKind::Forceps) {
        const double open = (1.0 - std::clamp(t.grip, 0.0, 1.0)) * kForcepsOpenHalfAngleDeg *
                            std::numbers::pi / 180;
        for (int side : {-1, 1}) {
          Eigen::Affine3d jaw = pose;
          jaw.translate(Vec3(0, 0, kForcepsJawLength));
          jaw.rotate(Eigen::AngleAxisd(-side * open, Vec3::UnitY()));
          jaw.translate(Vec3(side * 0.12, 0, -kForcepsJawLength));
          set_mat4(program, "u_model", to_mat4(jaw));
          glBindVertexArray(tool_jaw.vao);
          glDrawElements(GL_TRIANGLES, static_cast<GLsizei>(tool_jaw.index_count), GL_UNSIGNED_INT,
                         nullptr);
          stats.triangles += tool_jaw.index_count / 3;
          ++stats.draw_calls;
        }
      }
    }
  }

  // `rects` as triangles at the near plane (clip z −1, depth 0) into cover_vbo; the vertex count.
  // The colour attribute is the constant `rgba`.
  size_t rect_triangles(std::span<const PixelRect> rects, int width, int height,
                        const std::array<float, 4>& rgba, FrameStats& stats) {
    cover_xyz.clear();
    const float w = static_cast<float>(width), h = static_cast<float>(height);
    for (const PixelRect& r : rects) {
      const float x0 = std::clamp(r.x0, 0.0f, w), x1 = std::clamp(r.x1, 0.0f, w);
      const float y0 = std::clamp(r.y0, 0.0f, h), y1 = std::clamp(r.y1, 0.0f, h);
      if (!(x1 > x0 && y1 > y0)) continue;  // empty, off the window, or NaN
      // Clip space: x right, y up (pixel rows grow downward).
      const float l = 2 * x0 / w - 1, rt = 2 * x1 / w - 1, top = 1 - 2 * y0 / h,
                  bottom = 1 - 2 * y1 / h;
      const std::pair<float, float> corners[6] = {{l, bottom}, {rt, bottom}, {rt, top},
                                                  {l, bottom}, {rt, top},    {l, top}};
      for (const auto& [x, y] : corners) cover_xyz.insert(cover_xyz.end(), {x, y, -1.0f});
    }
    if (cover_xyz.empty()) return 0;
    upload(GL_ARRAY_BUFFER, cover_vbo, cover_xyz.data(), cover_xyz.size() * sizeof(float),
           cover_bytes, stats);
    glUseProgram(overlay_program);
    set_mat4(overlay_program, "u_view_proj", Mat4f::Identity());
    glBindVertexArray(cover_vao);
    glVertexAttrib4f(1, rgba[0], rgba[1], rgba[2], rgba[3]);
    const size_t n = cover_xyz.size() / 3;
    ++stats.draw_calls;
    stats.triangles += static_cast<uint32_t>(n / 3);
    return n;
  }

  // The covered rectangles into the depth buffer at the near plane, colour untouched: every later
  // pass's depth test (GL_LEQUAL) then fails there before its fragment shader runs.
  void cover(std::span<const PixelRect> rects, int width, int height, FrameStats& stats) {
    const size_t n = rect_triangles(rects, width, height, {0, 0, 0, 0}, stats);
    if (n == 0) return;
    glColorMask(GL_FALSE, GL_FALSE, GL_FALSE, GL_FALSE);
    glEnable(GL_DEPTH_TEST);
    glDepthFunc(GL_ALWAYS);
    glDepthMask(GL_TRUE);
    glDrawArrays(GL_TRIANGLES, 0, static_cast<GLsizei>(n));
    glColorMask(GL_TRUE, GL_TRUE, GL_TRUE, GL_TRUE);
    glDepthFunc(GL_LEQUAL);
    glDisable(GL_DEPTH_TEST);
    glBindVertexArray(0);
  }

  void draw_view(const RenderSnapshot& s, const Microscope& m, const RenderOptions& options,
                 const Camera& cam, const Eigen::Affine3d& eye, FrameStats& stats) {
    const Mat4f eye_m = to_mat4(eye);
    // The iris texture follows the pupil: re-baked (a rare allocation) when its ratio to the
    // iris root moves by more than half a percent, or the colour option changes.
    const int colour = options.blue_iris ? 1 : 0;
    const double ratio = pupil_r / std::max(iris_outer_r, 0.1);
    if (colour != iris_baked_colour || std::abs(ratio - iris_baked_ratio) > 0.005) {
      make_texture(bake_iris_disc(iris_polar[colour], ratio), iris_texture);
      iris_baked_colour = colour;
      iris_baked_ratio = ratio;
    }
    for (GLuint program : body_programs) {
      glUseProgram(program);
      set_mat4(program, "u_view_proj", cam.view_proj);
      set_mat4(program, "u_model", eye_m);
      set_vec3(program, "u_camera", cam.eye);
      set_vec3(program, "u_to_light", kToLight);
      set_float(program, "u_focus_z", m.focus_z_mm);
      set_float(program, "u_dof_mm", std::max(m.depth_of_field_mm, 0.1));
      set_float(program, "u_pupil_r", pupil_r);
      set_float(program, "u_iris_outer_r", iris_outer_r);
      set_float(program, "u_limbus_r", sclera_hole_r());
      set_float(program, "u_globe_centre_z", globe_centre_z);
      set_float(program, "u_globe_r", globe_r);
      glUniform1i(glGetUniformLocation(program, "u_texture"), 0);
    }
    for (Look look : {Look::LensSurface, Look::LensInterior})
      lens_map->bind(body_programs[static_cast<int>(look)], 1);
    glActiveTexture(GL_TEXTURE0);

    auto draw_body = [&](size_t i) {
      const BodySlot& slot = bodies[i];
      if (slot.index_count == 0) return;
      const Look look = s.bodies[i].look;
      glUseProgram(body_programs[static_cast<int>(look)]);
      if (look == Look::Iris) glBindTexture(GL_TEXTURE_2D, iris_texture);
      if (look == Look::Sclera) glBindTexture(GL_TEXTURE_2D, sclera_texture);
      if (look == Look::LensSurface || look == Look::LensInterior)
        set_float(body_programs[static_cast<int>(look)], "u_reflex_mu",
                  s.bodies[i].reflex_attenuation_per_mm);
      // Closed bodies show only their outside; open membranes both sides.
      const bool closed = look == Look::Sclera || look == Look::LensSurface || look == Look::Cornea;
      if (closed) glEnable(GL_CULL_FACE);
      glCullFace(GL_BACK);
      glBindVertexArray(slot.vao);
      glDrawElements(GL_TRIANGLES, static_cast<GLsizei>(slot.index_count), GL_UNSIGNED_INT,
                     nullptr);
      stats.triangles += slot.index_count / 3;
      ++stats.draw_calls;
      glDisable(GL_CULL_FACE);
    };

    // 1–2. Opaque, roughly front to back so the depth test rejects hidden fragments early:
    // instruments, exposed nucleus, lens (red reflex), iris, and the sclera (its discard) last.
    glEnable(GL_DEPTH_TEST);
    glDepthFunc(GL_LEQUAL);
    glDepthMask(GL_TRUE);
    glDisable(GL_BLEND);
    glUseProgram(body_programs[shaders::kLookTool]);
    draw_tools(s, body_programs[shaders::kLookTool], true, stats);
    for (Look look : {Look::LensInterior, Look::LensSurface, Look::Iris, Look::Sclera})
      for (size_t i = 0; i < s.bodies.size(); ++i)
        if (s.bodies[i].look == look) draw_body(i);
    lens_map->draw_fundus(body_programs[static_cast<int>(Look::LensSurface)], stats);

    // 3. Shadows: blended once per pixel (stencil), only where tissue is in front of nothing.
    glEnable(GL_BLEND);
    glBlendFunc(GL_SRC_ALPHA, GL_ONE_MINUS_SRC_ALPHA);
    if (options.shadows && !s.tools.empty()) {
      glUseProgram(shadow_program);
      set_mat4(shadow_program, "u_view_proj", cam.view_proj);
      set_mat4(shadow_program, "u_eye", eye_m);
      set_mat4(shadow_program, "u_eye_inv", to_mat4(eye.inverse()));
      set_vec3(shadow_program, "u_light_dir", -kToLight);
      set_float(shadow_program, "u_pupil_r", pupil_r);
      set_float(shadow_program, "u_iris_z", iris_z);
      set_float(shadow_program, "u_lens_a", lens_a);
      set_float(shadow_program, "u_lens_c", lens_c);
      set_float(shadow_program, "u_iris_outer_r", iris_outer_r);
      glDepthMask(GL_FALSE);
      glEnable(GL_STENCIL_TEST);
      glStencilFunc(GL_NOTEQUAL, 1, 0xff);
      glStencilOp(GL_KEEP, GL_KEEP, GL_REPLACE);
      glEnable(GL_POLYGON_OFFSET_FILL);
      glPolygonOffset(-2.0f, -2.0f);
      draw_tools(s, shadow_program, false, stats);
      glDisable(GL_POLYGON_OFFSET_FILL);
      glDisable(GL_STENCIL_TEST);
    }

    // 4. Membranes, back to front: capsule (on the lens, pulled forward), its edges, cornea.
    glDepthMask(GL_FALSE);
    glEnable(GL_POLYGON_OFFSET_FILL);
    glPolygonOffset(-1.0f, -4.0f);
    for (size_t i = 0; i < s.bodies.size(); ++i)
      if (s.bodies[i].look == Look::Capsule) draw_body(i);
    glDisable(GL_POLYGON_OFFSET_FILL);
    glBindVertexArray(overlay_vao);
    glUseProgram(overlay_program);
    set_mat4(overlay_program, "u_view_proj", cam.view_proj);
    if (edges_end > 0) {
      glEnable(GL_POLYGON_OFFSET_FILL);
      glPolygonOffset(-1.0f, -8.0f);
      glDrawArrays(GL_TRIANGLES, 0, static_cast<GLsizei>(edges_end));
      glDisable(GL_POLYGON_OFFSET_FILL);
      ++stats.draw_calls;
      stats.triangles += static_cast<uint32_t>(edges_end / 3);
    }
    for (size_t i = 0; i < s.bodies.size(); ++i)
      if (s.bodies[i].look == Look::Cornea) draw_body(i);

    // 5. Overlays on top.
    if (overlay.size() > edges_end) {
      glDisable(GL_DEPTH_TEST);
      glUseProgram(overlay_program);
      glBindVertexArray(overlay_vao);
      glDrawArrays(GL_TRIANGLES, static_cast<GLint>(edges_end),
                   static_cast<GLsizei>(overlay.size() - edges_end));
      ++stats.draw_calls;
      stats.triangles += static_cast<uint32_t>((overlay.size() - edges_end) / 3);
    }
    glDepthMask(GL_TRUE);
    glDisable(GL_BLEND);
    glDisable(GL_DEPTH_TEST);
    glBindVertexArray(0);
  }
};

Renderer::Renderer(const RenderOptions& options) : impl_(new Impl), options_(options) {
  try {
    if (epoxy_gl_version() < 33 || epoxy_is_desktop_gl() == 0)
      throw RenderError("renderer: needs desktop OpenGL 3.3 core, the context has " +
                        std::to_string(epoxy_gl_version() / 10) + "." +
                        std::to_string(epoxy_gl_version() % 10));
    Impl& im = *impl_;
    for (int look = 0; look < shaders::kLookCount; ++look) {
      const std::string fragment =
          "#version 330 core\n#define LOOK " + std::to_string(look) + "\n" + shaders::kBodyFragment;
      const std::string name = "body look " + std::to_string(look);
      im.body_programs[look] = link(shaders::kBodyVertex, fragment.c_str(), name.c_str());
    }
    im.lens_map = std::make_unique<LensReflexMap>();
    im.shadow_program = link(shaders::kShadowVertex, shaders::kShadowFragment, "shadow");
    im.overlay_program = link(shaders::kOverlayVertex, shaders::kOverlayFragment, "overlay");
    im.iris_polar[0] = make_iris_texture(false);
    im.iris_polar[1] = make_iris_texture(true);
    glGenTextures(1, &im.iris_texture);
    im.sclera_texture = Impl::make_texture(make_sclera_texture());
    for (int k = 0; k < Impl::kToolKinds; ++k) {
      const ToolMeshes meshes = make_tool_mesh(static_cast<ToolKind>(k));
      im.make_tool(im.tool_bodies[k], meshes.body);
      if (static_cast<ToolKind>(k) == ToolKind::Forceps) im.make_tool(im.tool_jaw, meshes.jaw);
    }
    glGenVertexArrays(1, &im.overlay_vao);
    glGenBuffers(1, &im.overlay_vbo);
    glBindVertexArray(im.overlay_vao);
    glBindBuffer(GL_ARRAY_BUFFER, im.overlay_vbo);
    constexpr GLsizei stride = sizeof(Impl::OverlayVertex);
    glVertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, stride, nullptr);
    glEnableVertexAttribArray(0);
    glVertexAttribPointer(1, 4, GL_FLOAT, GL_FALSE, stride,
                          reinterpret_cast<const void*>(3 * sizeof(float)));
    glEnableVertexAttribArray(1);
    glGenVertexArrays(1, &im.cover_vao);
    glGenBuffers(1, &im.cover_vbo);
    glBindVertexArray(im.cover_vao);
    glBindBuffer(GL_ARRAY_BUFFER, im.cover_vbo);
    glVertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, 3 * sizeof(float), nullptr);
    glEnableVertexAttribArray(0);  // the colour (attribute 1) is a constant: rect_triangles
    glBindVertexArray(0);
    im.overlay.reserve(8192);
  } catch (...) {
    delete impl_;
    throw;
  }
}

Renderer::~Renderer() {
  Impl& im = *impl_;
  for (GLuint program : im.body_programs) glDeleteProgram(program);
  glDeleteProgram(im.shadow_program);
  glDeleteProgram(im.overlay_program);
  glDeleteTextures(1, &im.iris_texture);
  glDeleteTextures(1, &im.sclera_texture);
  for (auto& slot : im.bodies) {
    glDeleteVertexArrays(1, &slot.vao);
    const GLuint buffers[4] = {slot.positions, slot.normals, slot.indices, slot.pieces};
    glDeleteBuffers(4, buffers);
  }
  for (auto& slot : im.tool_bodies) {
    glDeleteVertexArrays(1, &slot.vao);
    glDeleteBuffers(3, slot.buffers);
  }
  glDeleteVertexArrays(1, &im.tool_jaw.vao);
  glDeleteBuffers(3, im.tool_jaw.buffers);
  glDeleteVertexArrays(1, &im.overlay_vao);
  glDeleteBuffers(1, &im.overlay_vbo);
  glDeleteVertexArrays(1, &im.cover_vao);
  glDeleteBuffers(1, &im.cover_vbo);
  im.lens_map.reset();
  delete impl_;
}

FrameStats Renderer::draw(const RenderSnapshot& snapshot, const Microscope& microscope, int width,
                          int height, std::span<const PixelRect> covered) {
  FrameStats stats;
  Impl& im = *impl_;
  if (width <= 0 || height <= 0) return stats;
  im.upload_bodies(snapshot, stats);

  // The globe turns about its centre; instruments stay where the hands hold them.
  const Vec3 centre(0, 0, im.globe_centre_z);
  Eigen::Affine3d eye = Eigen::Affine3d::Identity();
  eye.translate(centre);
  eye.rotate(snapshot.globe_rotation.normalized());
  eye.translate(-centre);

  const bool stereo = options_.stereo == StereoMode::SideBySide;
  const int view_w = stereo ? width / 2 : width;
  const double px_mm = microscope.field_mm / std::max(std::min(view_w, height), 1);
  im.build_overlay(snapshot, eye, px_mm, options_.guidance && snapshot.show_guidance);
  size_t overlay_bytes = im.overlay_capacity * sizeof(Impl::OverlayVertex);
  Impl::upload(GL_ARRAY_BUFFER, im.overlay_vbo, im.overlay.data(),
               im.overlay.size() * sizeof(Impl::OverlayVertex), overlay_bytes, stats);
  im.overlay_capacity = overlay_bytes / sizeof(Impl::OverlayVertex);

  glDisable(GL_SCISSOR_TEST);
  glViewport(0, 0, width, height);
  glClearColor(0.03f, 0.025f, 0.025f, 1.0f);
  glClearDepth(1.0);
  glClearStencil(0);
  glEnable(GL_SCISSOR_TEST);
  glScissor(0, 0, width, height);
  glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT | GL_STENCIL_BUFFER_BIT);
  glDisable(GL_SCISSOR_TEST);
  im.cover(covered, width, height, stats);

  if (!stereo) {
    im.draw_view(snapshot, microscope, options_, make_camera(microscope, 0, width, height), eye,
                 stats);
  } else {
    for (int side = 0; side < 2; ++side) {
      glViewport(side * view_w, 0, view_w, height);
      // Left eye (left half) sits at −x; each view clears its own stencil for the shadows.
      const double offset = (side == 0 ? -0.5 : 0.5) * microscope.stereo_base_mm;
      glEnable(GL_SCISSOR_TEST);
      glScissor(side * view_w, 0, view_w, height);
      glClear(GL_STENCIL_BUFFER_BIT);
      glDisable(GL_SCISSOR_TEST);
      im.draw_view(snapshot, microscope, options_, make_camera(microscope, offset, view_w, height),
                   eye, stats);
    }
    glViewport(0, 0, width, height);
  }
  glUseProgram(0);
  return stats;
}

FrameStats Renderer::fill(std::span<const PixelRect> rects, const std::array<float, 4>& rgba,
                          int width, int height) {
  FrameStats stats;
  if (width <= 0 || height <= 0) return stats;
  const size_t n = impl_->rect_triangles(rects, width, height, rgba, stats);
  if (n == 0) return stats;
  glViewport(0, 0, width, height);
  glDisable(GL_DEPTH_TEST);
  glDisable(GL_BLEND);
  glDrawArrays(GL_TRIANGLES, 0, static_cast<GLsizei>(n));
  glBindVertexArray(0);
  glUseProgram(0);
  return stats;
}

std::array<double, 2> project_to_pixel(const Microscope& microscope, const Vec3& point_mm,
                                       int width, int height) {
  const Camera cam = make_camera(microscope, 0, width, height);
  const Eigen::Vector4f clip = cam.view_proj * Eigen::Vector4f(static_cast<float>(point_mm.x()),
                                                               static_cast<float>(point_mm.y()),
                                                               static_cast<float>(point_mm.z()), 1);
  const double x = clip.x() / clip.w(), y = clip.y() / clip.w();
  return {(x + 1) / 2 * width, (1 - y) / 2 * height};
}

}  // namespace phaco::render
