#pragma once
// GLSL 330 sources of the renderer (private to engine/render). One program draws every body and
// instrument, choosing its look by u_look; one projects the instruments' shadows; one draws the
// flat overlays (cut edges, guidance, contact rings) with per-vertex colour.
namespace phaco::render::shaders {

// Looks: 0..5 are render::Look, then the instruments.
constexpr int kLookTool = 6;
constexpr int kLookCount = 7;

inline constexpr const char* kBodyVertex = R"(#version 330 core
layout(location = 0) in vec3 a_pos;
layout(location = 1) in vec3 a_normal;
layout(location = 2) in float a_piece;  // lens: which fragment (BodyView::piece); else 0
uniform mat4 u_model;      // body or instrument frame -> eye frame after globe rotation
uniform mat4 u_view_proj;
out vec3 v_local;          // body frame (eye frame before globe rotation) or instrument frame
out vec3 v_world;
out vec3 v_normal;
flat out float v_piece;
void main() {
  vec4 w = u_model * vec4(a_pos, 1.0);
  v_local = a_pos;
  v_piece = a_piece;
  v_world = w.xyz;
  v_normal = mat3(u_model) * a_normal;
  gl_Position = u_view_proj * w;
}
)";

// Compiled once per look with "#version 330 core" and "#define LOOK n" put in front, so each
// program carries only its own branch and only the sclera's has a discard (which would otherwise
// turn off llvmpipe's early depth test for every body).
inline constexpr const char* kBodyFragment = R"(
in vec3 v_local;
in vec3 v_world;
in vec3 v_normal;
uniform vec3 u_camera;      // eye position, mm
uniform vec3 u_to_light;    // unit, toward the microscope's illuminator
uniform float u_focus_z;
uniform float u_dof_mm;
uniform sampler2D u_texture;  // iris: disc of radius u_iris_outer_r; sclera: globe seen from +z
uniform float u_limbus_r, u_globe_centre_z, u_globe_r, u_pupil_r, u_iris_outer_r;
uniform vec3 u_tool_colour;
uniform float u_glow;       // phaco tip ultrasound glow 0..1
uniform float u_glow_length;
out vec4 o_colour;

#if LOOK == 4 || LOOK == 5
// The lens seen from the microscope (lens_reflex.hpp): light from the fundus returns through the
// lens, dimmed by exp(-u_reflex_mu t) where t is the lens's remaining thickness on the line
// through this point; the rest of what the eye sees is the illuminator's light scattered back by
// the cataract's nucleus (amber), lit by the top surface's normal. So a trench's floor glows
// brighter and redder as the nucleus under it thins: the depth cue surgeons sculpt by.
uniform sampler2D u_lens_map;  // r: thickness mm; g, b: top normal x, y; a: 1 on the lens
uniform vec2 u_lens_map_origin;
uniform float u_lens_map_span;
uniform float u_reflex_mu;     // 1/mm (0: a clear lens)
uniform mat4 u_model;          // the globe's rotation (turns the map's normal into the eye frame)
flat in float v_piece;
vec4 lens_map(vec2 xy) {
  return texture(u_lens_map, (xy - u_lens_map_origin) / u_lens_map_span);
}
// lit: the illuminator's light on the surface, 0..1; facing: the surface normal's z (body frame).
vec3 lens_colour(float thickness, float lit, float facing, float k) {
  vec3 reflex = mix(vec3(0.42, 0.05, 0.02), vec3(0.98, 0.40, 0.12), k);
  // A steep face (a trench's wall) bends the fundus's light away from the microscope: its reflex
  // dims, so both walls outline the glowing floor.
  float through = exp(-u_reflex_mu * thickness) * mix(0.45, 1.0, facing);
  // Fragments apart: each piece's nucleus a shade lighter or darker than its neighbours.
  float tint = 0.86 + 0.28 * fract(v_piece * 0.618034);
  vec3 haze = tint * vec3(0.36, 0.23, 0.04) * (0.25 + 0.75 * lit);
  return reflex * through + haze * (1.0 - through);
}
#endif

void main() {
  vec3 n = normalize(v_normal);
  vec3 to_eye = normalize(u_camera - v_world);
  if (dot(n, to_eye) < 0.0) n = -n;  // open membranes are seen from either side
  vec3 h = normalize(u_to_light + to_eye);
  float diffuse = max(dot(n, u_to_light), 0.0);
  float nh = max(dot(n, h), 0.0);
  // Depth of field: sharp within half the depth of field about the focal plane, then texture
  // detail (mipmap bias) and contrast fade toward the look's mean colour.
  float blur = clamp((abs(v_world.z - u_focus_z) - 0.5 * u_dof_mm) / (1.5 * u_dof_mm), 0.0, 1.0);
  vec3 c;
  vec3 mean;
#if LOOK == 0  // sclera; the globe's front cap inside the limbus belongs to the cornea
  if (dot(v_local.xy, v_local.xy) < u_limbus_r * u_limbus_r && v_local.z > u_globe_centre_z)
    discard;
  vec3 albedo = texture(u_texture, v_local.xy / (2.0 * u_globe_r) + 0.5).rgb;
  float wet = nh * nh;
  wet *= wet;
  wet *= wet;
  c = albedo * (0.35 + 0.65 * diffuse) + 0.2 * wet * wet;
  mean = vec3(0.85, 0.8, 0.77) * (0.35 + 0.65 * diffuse);
#elif LOOK == 1  // iris
  vec3 albedo = texture(u_texture, v_local.xy / (2.0 * u_iris_outer_r) + 0.5).rgb;
  c = albedo * (0.45 + 0.7 * diffuse);
  mean = albedo;
#elif LOOK == 2  // cornea: a clear film, a Fresnel rim and the illuminator's reflection
  float facing = 1.0 - max(dot(n, to_eye), 0.0);
  float fresnel = facing * facing * facing;
  fresnel *= facing * facing;
  float highlight = pow(nh, 400.0);
  o_colour = vec4(0.92, 0.96, 1.0, clamp(0.06 + 0.6 * fresnel + highlight, 0.0, 1.0));
  return;
#elif LOOK == 3  // anterior capsule: a faint sheen over the red reflex
  float highlight = pow(nh, 60.0);
  o_colour = vec4(0.86, 0.9, 0.95, clamp(0.16 + 0.5 * highlight, 0.0, 1.0));
  return;
#elif LOOK == 4 || LOOK == 5  // the lens: red reflex from behind, brightest on the axis
  float k = clamp(1.0 - 0.6 * dot(v_local.xy, v_local.xy) / (u_pupil_r * u_pupil_r), 0.0, 1.0);
  vec4 map = lens_map(v_local.xy);
  float lit = diffuse, facing = 1.0;
#if LOOK == 5
  // Sculpted faces take the sculpted surface's normal (the map's, at the trench's scale, not the
  // tets' facets), so the walls read as walls (eye frame, as the illuminator is). No glint: on
  // the floor's tet-sized bumps it would only sparkle.
  if (map.a > 0.5) {
    facing = sqrt(max(1.0 - dot(map.gb, map.gb), 0.0));
    lit = max(dot(mat3(u_model) * vec3(map.gb, facing), u_to_light), 0.0);
  }
  nh = 0.0;
#endif
  c = lens_colour(map.r, lit, facing, k) + 0.15 * pow(nh, 80.0);
  mean = c;
#else  // instruments: polished steel
  c = u_tool_colour * (0.35 + 0.6 * diffuse) + vec3(0.55) * pow(nh, 40.0);
  float glow = u_glow * clamp(1.0 - v_local.z / u_glow_length, 0.0, 1.0);
  c = mix(c, vec3(1.0, 0.9, 0.55), glow);
  mean = c;
  blur *= 0.5;  // keep the instruments legible out of focus
#endif
  o_colour = vec4(mix(c, mean, 0.35 * blur), 1.0);
}
)";

// Instrument shadows: each vertex is carried along the light onto the tissue under it (the lens's
// anterior half-ellipsoid inside the pupil, the iris plane outside), in the eye frame.
inline constexpr const char* kShadowVertex = R"(#version 330 core
layout(location = 0) in vec3 a_pos;
uniform mat4 u_model;       // instrument frame -> world
uniform mat4 u_eye;         // eye frame -> world (globe rotation)
uniform mat4 u_eye_inv;
uniform mat4 u_view_proj;
uniform vec3 u_light_dir;   // direction the light travels, eye frame, unit, z < 0
uniform float u_pupil_r, u_iris_z, u_lens_a, u_lens_c;
out vec2 v_eye_xy;
float receiver(vec2 xy) {
  float r = length(xy);
  if (r < u_pupil_r) return u_lens_c * sqrt(max(1.0 - (r * r) / (u_lens_a * u_lens_a), 0.0));
  return u_iris_z;
}
void main() {
  vec3 p = (u_eye_inv * (u_model * vec4(a_pos, 1.0))).xyz;
  float t = 0.0;
  for (int i = 0; i < 3; ++i) t = (receiver((p + t * u_light_dir).xy) - p.z) / u_light_dir.z;
  vec3 q = p + t * u_light_dir;
  q.z = receiver(q.xy) + 0.02;
  v_eye_xy = q.xy;
  gl_Position = u_view_proj * (u_eye * vec4(q, 1.0));
}
)";

inline constexpr const char* kShadowFragment = R"(#version 330 core
in vec2 v_eye_xy;
uniform float u_iris_outer_r;  // receivers end at the iris root (the sclera lies far below)
out vec4 o_colour;
void main() {
  if (dot(v_eye_xy, v_eye_xy) > u_iris_outer_r * u_iris_outer_r) discard;
  o_colour = vec4(0.0, 0.0, 0.0, 0.45);
}
)";

inline constexpr const char* kOverlayVertex = R"(#version 330 core
layout(location = 0) in vec3 a_pos;
layout(location = 1) in vec4 a_colour;
uniform mat4 u_view_proj;
out vec4 v_colour;
void main() {
  v_colour = a_colour;
  gl_Position = u_view_proj * vec4(a_pos, 1.0);
}
)";

inline constexpr const char* kOverlayFragment = R"(#version 330 core
in vec4 v_colour;
out vec4 o_colour;
void main() { o_colour = v_colour; }
)";

}  // namespace phaco::render::shaders
