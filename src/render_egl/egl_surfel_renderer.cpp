#include "render_egl/egl_surfel_renderer.hpp"

#define GL_GLEXT_PROTOTYPES 1
#include <GL/glcorearb.h>

#include <cmath>
#include <cstring>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "core/worker_pool.hpp"
#include "render_egl/egl_context.hpp"
#include "render_egl/surfel_shaders.hpp"

namespace slam_mms {
namespace {

// One surfel as uploaded: position + radius, normal, id (32 bytes).
struct GpuSurfel {
  float pos_radius[4];
  float normal[3];
  int32_t id;
};
static_assert(sizeof(GpuSurfel) == 32, "GpuSurfel layout");

// The draw-order surfels [begin, end) of `input` into `out` (out[0] is surfel `begin`).
void PackSurfels(const SurfelRenderInput& input, size_t begin, size_t end, GpuSurfel* out) {
  for (size_t k = begin; k < end; ++k) {
    const size_t id = input.ids != nullptr ? input.ids[k] : k;
    const Surfel& s = input.surfels[id];
    GpuSurfel& g = out[k - begin];
    g.pos_radius[0] = s.position.x();
    g.pos_radius[1] = s.position.y();
    g.pos_radius[2] = s.position.z();
    g.pos_radius[3] = s.radius;
    g.normal[0] = s.normal.x();
    g.normal[1] = s.normal.y();
    g.normal[2] = s.normal.z();
    g.id = static_cast<int32_t>(id);
  }
}

Status GlError(const char* what) {
  const GLenum e = glGetError();
  if (e == GL_NO_ERROR) return OkStatus();
  std::ostringstream os;
  os << "EglSurfelRenderer: OpenGL error 0x" << std::hex << e << " in " << what;
  return InternalError(os.str());
}

StatusOr<GLuint> CompileShader(GLenum type, const char* source) {
  const GLuint s = glCreateShader(type);
  glShaderSource(s, 1, &source, nullptr);
  glCompileShader(s);
  GLint ok = 0;
  glGetShaderiv(s, GL_COMPILE_STATUS, &ok);
  if (!ok) {
    char log[2048] = {0};
    glGetShaderInfoLog(s, sizeof(log) - 1, nullptr, log);
    glDeleteShader(s);
    return UnavailableError(std::string("EglSurfelRenderer: shader compilation failed: ") + log);
  }
  return s;
}

}  // namespace

struct EglSurfelRenderer::Impl {
  Impl(const SurfelRendererOptions& o, int num_threads)
      : options(o), projection(*RangeProjection::Create(o.projection)), pool(num_threads) {}
  ~Impl() { Release(); }

  Status Init();
  void Release();

  SurfelRendererOptions options;
  RangeProjection projection;
  internal::EglContext egl;
  GLuint program = 0, vao = 0, vbo = 0, fbo = 0, ray_tex = 0;
  GLuint color_tex[3] = {0, 0, 0};
  GLuint depth_rb = 0;
  GLint loc_R = -1, loc_t = -1;
  size_t vbo_capacity = 0;
  // The host side of a render (gathering the surfels, unpacking the read-back images) is split
  // over these threads; GL is called from the calling thread only.
  internal::WorkerPool pool;
  std::vector<GpuSurfel> staging;  // only where the buffer cannot be mapped
  std::vector<float> read_vertex, read_normal;
  std::vector<int32_t> read_index;
};

Status EglSurfelRenderer::Impl::Init() {
  SLAM_MMS_RETURN_IF_ERROR(egl.Open());
  const int rows = projection.rows();
  const int cols = projection.cols();
  GLint max_size = 0;
  glGetIntegerv(GL_MAX_TEXTURE_SIZE, &max_size);
  if (cols > max_size || rows > max_size) {
    std::ostringstream os;
    os << "EglSurfelRenderer: image " << rows << " x " << cols << " exceeds GL_MAX_TEXTURE_SIZE "
       << max_size;
    return UnavailableError(os.str());
  }
  // Program.
  SLAM_MMS_ASSIGN_OR_RETURN(GLuint vs,
                            CompileShader(GL_VERTEX_SHADER, internal::kSurfelVertexShader));
  SLAM_MMS_ASSIGN_OR_RETURN(GLuint gs,
                            CompileShader(GL_GEOMETRY_SHADER, internal::kSurfelGeometryShader));
  SLAM_MMS_ASSIGN_OR_RETURN(GLuint fs,
                            CompileShader(GL_FRAGMENT_SHADER, internal::kSurfelFragmentShader));
  program = glCreateProgram();
  glAttachShader(program, vs);
  glAttachShader(program, gs);
  glAttachShader(program, fs);
  glLinkProgram(program);
  glDeleteShader(vs);
  glDeleteShader(gs);
  glDeleteShader(fs);
  GLint linked = 0;
  glGetProgramiv(program, GL_LINK_STATUS, &linked);
  if (!linked) {
    char log[2048] = {0};
    glGetProgramInfoLog(program, sizeof(log) - 1, nullptr, log);
    return UnavailableError(std::string("EglSurfelRenderer: program link failed: ") + log);
  }
  glUseProgram(program);
  const RangeProjectionOptions& po = projection.options();
  const double fov = (po.fov_up_deg - po.fov_down_deg) * M_PI / 180.0;
  glUniform1f(glGetUniformLocation(program, "u_fov_up"),
              static_cast<float>(po.fov_up_deg * M_PI / 180.0));
  glUniform1f(glGetUniformLocation(program, "u_rows_per_rad"), static_cast<float>(rows / fov));
  glUniform1f(glGetUniformLocation(program, "u_cols_per_rad"),
              static_cast<float>(cols) / (2.0f * 3.14159265358979f));
  glUniform1f(glGetUniformLocation(program, "u_rows"), static_cast<float>(rows));
  glUniform1f(glGetUniformLocation(program, "u_cols"), static_cast<float>(cols));
  glUniform1f(glGetUniformLocation(program, "u_min_r"), static_cast<float>(po.min_range_m));
  glUniform1f(glGetUniformLocation(program, "u_max_r"), static_cast<float>(po.max_range_m));
  glUniform1f(glGetUniformLocation(program, "u_facing"),
              static_cast<float>(options.min_facing_cos));
  glUniform1i(glGetUniformLocation(program, "u_rays"), 0);
  loc_R = glGetUniformLocation(program, "u_R");
  loc_t = glGetUniformLocation(program, "u_t");
  SLAM_MMS_RETURN_IF_ERROR(GlError("program setup"));

  // Ray-direction texture (exactly RangeProjection's table).
  std::vector<float> rays(static_cast<size_t>(rows) * cols * 4);
  for (size_t i = 0; i < projection.ray_directions().size(); ++i) {
    const Eigen::Vector3f& d = projection.ray_directions()[i];
    rays[4 * i] = d.x();
    rays[4 * i + 1] = d.y();
    rays[4 * i + 2] = d.z();
    rays[4 * i + 3] = 0.0f;
  }
  glGenTextures(1, &ray_tex);
  glActiveTexture(GL_TEXTURE0);
  glBindTexture(GL_TEXTURE_2D, ray_tex);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
  glTexImage2D(GL_TEXTURE_2D, 0, GL_RGBA32F, cols, rows, 0, GL_RGBA, GL_FLOAT, rays.data());
  SLAM_MMS_RETURN_IF_ERROR(GlError("ray texture"));

  // FBO: vertex+range, normal (RGBA32F), index (R32I), 32-bit float depth.
  glGenFramebuffers(1, &fbo);
  glBindFramebuffer(GL_FRAMEBUFFER, fbo);
  glGenTextures(3, color_tex);
  const GLenum internal_formats[3] = {GL_RGBA32F, GL_RGBA32F, GL_R32I};
  const GLenum formats[3] = {GL_RGBA, GL_RGBA, GL_RED_INTEGER};
  const GLenum types[3] = {GL_FLOAT, GL_FLOAT, GL_INT};
  for (int i = 0; i < 3; ++i) {
    glBindTexture(GL_TEXTURE_2D, color_tex[i]);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
    glTexImage2D(GL_TEXTURE_2D, 0, static_cast<GLint>(internal_formats[i]), cols, rows, 0,
                 formats[i], types[i], nullptr);
    glFramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0 + i, GL_TEXTURE_2D, color_tex[i],
                           0);
  }
  glBindTexture(GL_TEXTURE_2D, ray_tex);
  glGenRenderbuffers(1, &depth_rb);
  glBindRenderbuffer(GL_RENDERBUFFER, depth_rb);
  glRenderbufferStorage(GL_RENDERBUFFER, GL_DEPTH_COMPONENT32F, cols, rows);
  glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, depth_rb);
  const GLenum draw_buffers[3] = {GL_COLOR_ATTACHMENT0, GL_COLOR_ATTACHMENT1, GL_COLOR_ATTACHMENT2};
  glDrawBuffers(3, draw_buffers);
  const GLenum fb_status = glCheckFramebufferStatus(GL_FRAMEBUFFER);
  if (fb_status != GL_FRAMEBUFFER_COMPLETE) {
    std::ostringstream os;
    os << "EglSurfelRenderer: framebuffer incomplete (0x" << std::hex << fb_status
       << "): RGBA32F/R32I/DEPTH32F attachments not renderable here";
    return UnavailableError(os.str());
  }
  glViewport(0, 0, cols, rows);
  glEnable(GL_DEPTH_TEST);
  glDepthFunc(GL_LESS);
  glDisable(GL_BLEND);
  glDisable(GL_CULL_FACE);

  // Vertex layout.
  glGenVertexArrays(1, &vao);
  glBindVertexArray(vao);
  glGenBuffers(1, &vbo);
  glBindBuffer(GL_ARRAY_BUFFER, vbo);
  glEnableVertexAttribArray(0);
  glVertexAttribPointer(0, 4, GL_FLOAT, GL_FALSE, sizeof(GpuSurfel), nullptr);
  glEnableVertexAttribArray(1);
  glVertexAttribPointer(1, 3, GL_FLOAT, GL_FALSE, sizeof(GpuSurfel),
                        reinterpret_cast<const void*>(offsetof(GpuSurfel, normal)));
  glEnableVertexAttribArray(2);
  glVertexAttribIPointer(2, 1, GL_INT, sizeof(GpuSurfel),
                         reinterpret_cast<const void*>(offsetof(GpuSurfel, id)));
  glPixelStorei(GL_PACK_ALIGNMENT, 4);
  const size_t n = static_cast<size_t>(rows) * cols;
  read_vertex.resize(4 * n);
  read_normal.resize(4 * n);
  read_index.resize(n);
  return GlError("setup");
}

void EglSurfelRenderer::Impl::Release() {
  if (egl.context != EGL_NO_CONTEXT && egl.MakeCurrent().ok()) {
    if (vbo) glDeleteBuffers(1, &vbo);
    if (vao) glDeleteVertexArrays(1, &vao);
    if (fbo) glDeleteFramebuffers(1, &fbo);
    if (color_tex[0]) glDeleteTextures(3, color_tex);
    if (ray_tex) glDeleteTextures(1, &ray_tex);
    if (depth_rb) glDeleteRenderbuffers(1, &depth_rb);
    if (program) glDeleteProgram(program);
  }
  egl.Close();
}

EglSurfelRenderer::EglSurfelRenderer(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
EglSurfelRenderer::~EglSurfelRenderer() = default;

StatusOr<std::unique_ptr<EglSurfelRenderer>> EglSurfelRenderer::Create(
    const SurfelRendererOptions& options, int num_threads) {
  SLAM_MMS_RETURN_IF_ERROR(options.Validate());
  if (num_threads < 1 || num_threads > 64) {
    return InvalidArgumentError("EglSurfelRenderer: num_threads = " + std::to_string(num_threads) +
                                "; must be in [1, 64]");
  }
  auto impl = std::make_unique<Impl>(options, num_threads);
  SLAM_MMS_RETURN_IF_ERROR(impl->Init());
  return std::unique_ptr<EglSurfelRenderer>(new EglSurfelRenderer(std::move(impl)));
}

std::string EglSurfelRenderer::Name() const { return "egl (" + impl_->egl.gl_renderer + ")"; }
const RangeProjection& EglSurfelRenderer::projection() const { return impl_->projection; }
const std::string& EglSurfelRenderer::gl_renderer() const { return impl_->egl.gl_renderer; }
const std::string& EglSurfelRenderer::gl_version() const { return impl_->egl.gl_version; }
const std::string& EglSurfelRenderer::egl_platform() const { return impl_->egl.platform; }
bool EglSurfelRenderer::IsSoftware() const {
  const std::string& r = impl_->egl.gl_renderer;
  return r.find("llvmpipe") != std::string::npos || r.find("softpipe") != std::string::npos ||
         r.find("swrast") != std::string::npos;
}

Status EglSurfelRenderer::Render(const SurfelRenderInput& input,
                                 const Eigen::Isometry3d& T_world_sensor, VertexNormalMap* out) {
  if (out == nullptr) return InvalidArgumentError("EglSurfelRenderer::Render: out is null");
  SLAM_MMS_RETURN_IF_ERROR(ValidateRenderInput(input));
  if (!T_world_sensor.matrix().allFinite()) {
    return InvalidArgumentError("EglSurfelRenderer::Render: T_world_sensor is not finite");
  }
  Impl& m = *impl_;
  SLAM_MMS_RETURN_IF_ERROR(m.egl.MakeCurrent());
  const int rows = m.projection.rows();
  const int cols = m.projection.cols();
  const size_t num_pixels = static_cast<size_t>(rows) * cols;

  // Upload the surfels in draw order: gathered by the pool's threads straight into the mapped
  // buffer (the old buffer storage is invalidated: the last render's read-back has finished with
  // it); where the driver cannot map it, through a staging copy and glBufferSubData.
  const size_t n = input.count();
  glUseProgram(m.program);
  glBindVertexArray(m.vao);
  glBindBuffer(GL_ARRAY_BUFFER, m.vbo);
  const size_t bytes = n * sizeof(GpuSurfel);
  if (bytes > m.vbo_capacity) {
    m.vbo_capacity = bytes + bytes / 4;
    glBufferData(GL_ARRAY_BUFFER, static_cast<GLsizeiptr>(m.vbo_capacity), nullptr, GL_STREAM_DRAW);
  }
  auto pack_into = [&](GpuSurfel* out) {
    m.pool.Run([&](int i) {
      size_t begin = 0, end = 0;
      m.pool.Range(i, n, &begin, &end);
      PackSurfels(input, begin, end, out + begin);
    });
  };
  if (bytes > 0) {
    void* mapped = glMapBufferRange(GL_ARRAY_BUFFER, 0, static_cast<GLsizeiptr>(bytes),
                                    GL_MAP_WRITE_BIT | GL_MAP_INVALIDATE_BUFFER_BIT);
    bool uploaded = false;
    if (mapped != nullptr) {
      pack_into(static_cast<GpuSurfel*>(mapped));
      // GL_FALSE: the store was lost while mapped (e.g. a display mode change); upload again.
      uploaded = glUnmapBuffer(GL_ARRAY_BUFFER) == GL_TRUE;
    }
    if (!uploaded) {
      glGetError();  // a failed map's error is answered by the fallback below
      m.staging.resize(n);
      pack_into(m.staging.data());
      glBufferSubData(GL_ARRAY_BUFFER, 0, static_cast<GLsizeiptr>(bytes), m.staging.data());
    }
  }
  const Eigen::Isometry3d T_sensor_world = T_world_sensor.inverse();
  const Eigen::Matrix3f R = T_sensor_world.linear().cast<float>();  // column-major
  const Eigen::Vector3f t = T_sensor_world.translation().cast<float>();
  glUniformMatrix3fv(m.loc_R, 1, GL_FALSE, R.data());
  glUniform3f(m.loc_t, t.x(), t.y(), t.z());

  glBindFramebuffer(GL_FRAMEBUFFER, m.fbo);
  const float zero[4] = {0.0f, 0.0f, 0.0f, 0.0f};
  const GLint minus_one[4] = {-1, -1, -1, -1};
  const float far_depth = 1.0f;
  glClearBufferfv(GL_COLOR, 0, zero);
  glClearBufferfv(GL_COLOR, 1, zero);
  glClearBufferiv(GL_COLOR, 2, minus_one);
  glClearBufferfv(GL_DEPTH, 0, &far_depth);
  glActiveTexture(GL_TEXTURE0);
  glBindTexture(GL_TEXTURE_2D, m.ray_tex);
  if (n > 0) glDrawArrays(GL_POINTS, 0, static_cast<GLsizei>(n));
  SLAM_MMS_RETURN_IF_ERROR(GlError("draw"));

  // Read back.
  glReadBuffer(GL_COLOR_ATTACHMENT0);
  glReadPixels(0, 0, cols, rows, GL_RGBA, GL_FLOAT, m.read_vertex.data());
  glReadBuffer(GL_COLOR_ATTACHMENT1);
  glReadPixels(0, 0, cols, rows, GL_RGBA, GL_FLOAT, m.read_normal.data());
  glReadBuffer(GL_COLOR_ATTACHMENT2);
  glReadPixels(0, 0, cols, rows, GL_RED_INTEGER, GL_INT, m.read_index.data());
  SLAM_MMS_RETURN_IF_ERROR(GlError("readback"));

  if (out->rows != rows || out->cols != cols || out->range.size() != num_pixels) {
    out->Reset(rows, cols);
  }
  m.pool.Run([&](int t) {
    size_t begin = 0, end = 0;
    m.pool.Range(t, num_pixels, &begin, &end);
    for (size_t i = begin; i < end; ++i) {
      const int32_t idx = m.read_index[i];
      if (idx < 0) {
        out->vertex[i].setZero();
        out->normal[i].setZero();
        out->range[i] = 0.0f;
        out->index[i] = -1;
        continue;
      }
      const float* v = &m.read_vertex[4 * i];
      const float* nn = &m.read_normal[4 * i];
      out->vertex[i] = Eigen::Vector3f(v[0], v[1], v[2]);
      out->range[i] = v[3];
      out->normal[i] = Eigen::Vector3f(nn[0], nn[1], nn[2]);
      out->index[i] = idx;
    }
  });
  return OkStatus();
}

}  // namespace slam_mms
