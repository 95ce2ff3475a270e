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
uniform mat4 u_model;      // body or instrument frame -> eye frame after globe rotation
uniform mat4 u_view_proj;
out vec3 v_local;          // body frame (eye frame before globe rotation) or instrument frame
out vec3 v_world;
out vec3 v_normal;
void main() {
  vec4 w = u_model * vec4(a_pos, 1.0);
  v_local = a_pos;
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
#elif LOOK == 4  // lens lit from behind by the fundus: the red reflex, brightest on the axis
  float k = clamp(1.0 - 0.6 * dot(v_local.xy, v_local.xy) / (u_pupil_r * u_pupil_r), 0.0, 1.0);
  c = mix(vec3(0.42, 0.05, 0.02), vec3(0.98, 0.40, 0.12), k) + 0.15 * pow(nh, 80.0);
  mean = c;
#elif LOOK == 5  // exposed nucleus: pale yellow, lit so trench walls read darker than its floor
  vec3 albedo = vec3(0.86, 0.77, 0.50);
  c = albedo * (0.25 + 0.75 * diffuse) + vec3(0.12, 0.02, 0.0);
  mean = albedo * 0.7;
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
