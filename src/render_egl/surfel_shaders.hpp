#pragma once
// GLSL 3.30 core shaders of EglSurfelRenderer. The geometry shader mirrors
// CpuSurfelRenderer::Impl::Splat (culling and the conservative pixel bounding box); the fragment
// shader does the exact pixel-centre ray / disc test. Keep the three in step.

namespace slam_mms::internal {

inline constexpr const char* kSurfelVertexShader = R"glsl(
#version 330 core
layout(location = 0) in vec4 a_pos_radius;
layout(location = 1) in vec3 a_normal;
layout(location = 2) in int a_id;
out vec4 v_pos_radius;
out vec3 v_normal;
flat out int v_id;
void main() {
  v_pos_radius = a_pos_radius;
  v_normal = a_normal;
  v_id = a_id;
  gl_Position = vec4(0.0, 0.0, 0.0, 1.0);
}
)glsl";

inline constexpr const char* kSurfelGeometryShader = R"glsl(
#version 330 core
layout(points) in;
layout(triangle_strip, max_vertices = 12) out;
in vec4 v_pos_radius[];
in vec3 v_normal[];
flat in int v_id[];
uniform mat3 u_R;
uniform vec3 u_t;
uniform float u_fov_up;
uniform float u_rows_per_rad;
uniform float u_cols_per_rad;
uniform float u_rows;
uniform float u_cols;
uniform float u_min_r;
uniform float u_max_r;
uniform float u_facing;
flat out vec3 g_p;
flat out vec3 g_n;
flat out float g_r2;
flat out int g_id;
const float kPi = 3.14159265358979;
const float kMargin = 1e-4;
const float kLinearMax = 0.1;

float CosLowerBound(float e) {
  float e2 = e * e;
  return 1.0 - e2 * (0.5 - e2 * (1.0 / 24.0 - e2 * (1.0 / 720.0)));
}

void EmitRect(float x0, float x1, float y0, float y1, vec3 p, vec3 n, float r2, int id) {
  vec2 lo = vec2(x0 / u_cols, y0 / u_rows) * 2.0 - 1.0;
  vec2 hi = vec2(x1 / u_cols, y1 / u_rows) * 2.0 - 1.0;
  vec2 c[4] = vec2[4](vec2(lo.x, lo.y), vec2(hi.x, lo.y), vec2(lo.x, hi.y), vec2(hi.x, hi.y));
  for (int i = 0; i < 4; ++i) {
    g_p = p;
    g_n = n;
    g_r2 = r2;
    g_id = id;
    gl_Position = vec4(c[i], 0.0, 1.0);
    EmitVertex();
  }
  EndPrimitive();
}

void main() {
  vec3 p = u_R * v_pos_radius[0].xyz + u_t;
  float radius = v_pos_radius[0].w;
  float d2 = dot(p, p);
  if (!(d2 >= u_min_r * u_min_r && d2 <= u_max_r * u_max_r)) return;
  float d = sqrt(d2);
  if (!(radius > 0.0) || !(radius < d)) return;
  vec3 n = u_R * v_normal[0];
  float n_dot_p = dot(n, p);
  if (!(-n_dot_p > u_facing * d)) return;
  float sin_a = radius / d;
  float a = sin_a / sqrt(1.0 - sin_a * sin_a) + kMargin;
  float rho2 = p.x * p.x + p.y * p.y;
  float rho = sqrt(rho2);
  float pitch = atan(p.z, rho);
  float e_pitch = a;
  float e_yaw = -1.0;
  if (a < kLinearMax && rho > 0.5 * d) {
    float inv_rho2 = 1.0 / rho2;
    vec3 g_yaw = vec3(-p.y * inv_rho2, p.x * inv_rho2, 0.0);
    float k = 1.0 / (d2 * rho);
    vec3 g_pitch = vec3(-p.x * p.z * k, -p.y * p.z * k, rho2 * k);
    float widen = radius * (1.0 + 2.0 * a);
    float margin = a * a + kMargin;
    float gy = dot(g_yaw, n);
    float gp = dot(g_pitch, n);
    e_yaw = widen * sqrt(max(0.0, dot(g_yaw, g_yaw) - gy * gy)) + margin;
    e_pitch = widen * sqrt(max(0.0, dot(g_pitch, g_pitch) - gp * gp)) + margin;
  }
  float v_lo = (u_fov_up - (pitch + e_pitch)) * u_rows_per_rad;
  float v_hi = (u_fov_up - (pitch - e_pitch)) * u_rows_per_rad;
  if (v_hi < 0.0 || v_lo >= u_rows) return;
  float row0 = max(0.0, floor(v_lo));
  float row1 = min(u_rows - 1.0, floor(v_hi));
  if (e_yaw < 0.0) {
    float elev = max(abs(pitch - a), abs(pitch + a));
    if (elev < 0.5 * kPi - 1e-3) {
      float s2 = sin_a / CosLowerBound(elev);
      if (s2 < 1.0) e_yaw = s2 / sqrt(1.0 - s2 * s2) + kMargin;
    }
  }
  float col0 = 0.0;
  float col1 = u_cols - 1.0;
  if (e_yaw >= 0.0) {
    float yaw = atan(p.y, p.x);
    float u = 0.5 * (1.0 - yaw / kPi) * u_cols;
    float hu = e_yaw * u_cols_per_rad;
    float c0 = floor(u - hu);
    float c1 = floor(u + hu);
    if (c1 - c0 + 1.0 < u_cols) {
      col0 = c0;
      col1 = c1;
    }
  }
  float r2 = radius * radius;
  int id = v_id[0];
  EmitRect(col0, col1 + 1.0, row0, row1 + 1.0, p, n, r2, id);
  if (col0 < 0.0) EmitRect(col0 + u_cols, col1 + 1.0 + u_cols, row0, row1 + 1.0, p, n, r2, id);
  if (col1 >= u_cols) EmitRect(col0 - u_cols, col1 + 1.0 - u_cols, row0, row1 + 1.0, p, n, r2, id);
}
)glsl";

inline constexpr const char* kSurfelFragmentShader = R"glsl(
#version 330 core
uniform sampler2D u_rays;
uniform float u_min_r;
uniform float u_max_r;
flat in vec3 g_p;
flat in vec3 g_n;
flat in float g_r2;
flat in int g_id;
layout(location = 0) out vec4 o_vertex;
layout(location = 1) out vec4 o_normal;
layout(location = 2) out int o_index;
void main() {
  vec3 ray = texelFetch(u_rays, ivec2(gl_FragCoord.xy), 0).xyz;
  float denom = dot(g_n, ray);
  if (!(denom < 0.0)) discard;
  float t = dot(g_n, g_p) / denom;
  vec3 h = t * ray - g_p;
  if (dot(h, h) > g_r2) discard;
  if (t < u_min_r || t > u_max_r) discard;
  gl_FragDepth = t / u_max_r;
  o_vertex = vec4(t * ray, t);
  o_normal = vec4(g_n, 0.0);
  o_index = g_id;
}
)glsl";

}  // namespace slam_mms::internal
