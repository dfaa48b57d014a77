#pragma once
// EglSurfelRenderer: the OpenGL SurfelRenderer on a headless EGL context (no X server). It produces
// the image defined in slam_mms/surfel/surfel_renderer.hpp, the same as CpuSurfelRenderer.
//
// Context: EGL_EXT_platform_device (eglQueryDevicesEXT; hardware devices first, e.g. NVIDIA), then
// EGL_MESA_platform_surfaceless (Mesa, llvmpipe on CPU-only machines), then the default display;
// OpenGL 4.5 core, else 3.3 core; no window surface (EGL_KHR_surfaceless_context).
// Pipeline: each surfel is one GL_POINTS vertex; a geometry shader culls it and emits a quad
// covering the pixel bounding box of its disc (a second or third quad where it wraps around the
// rear seam); the fragment shader intersects the pixel-centre ray (a float texture of
// RangeProjection::ray_directions) with the disc, discards misses and writes gl_FragDepth = t / max
// range (GL_LESS, 32-bit float depth). An FBO holds RGBA32F vertex+range, RGBA32F normal and R32I
// surfel-index attachments, read back with glReadPixels.
// Failure: if EGL or GL cannot start, Create returns Unavailable with the reason; nothing aborts.
//
// Thread safety: not thread-safe. The GL context is made current on the calling thread at each
// Render (so a renderer may move between threads, but must be used by one thread at a time).
// Move-only; the destructor releases the context.

#include <memory>
#include <string>

#include "slam_mms/surfel/surfel_renderer.hpp"

namespace slam_mms {

class EglSurfelRenderer final : public SurfelRenderer {
 public:
  /// Unavailable when no EGL display/context/FBO can be made; InvalidArgument for bad options or
  /// num_threads outside [1, 64]. num_threads (the calling thread included) share the host side of
  /// each render: gathering the surfels into the mapped vertex buffer and unpacking the read-back
  /// images (the image does not depend on it).
  static StatusOr<std::unique_ptr<EglSurfelRenderer>> Create(const SurfelRendererOptions& options,
                                                             int num_threads = 1);
  ~EglSurfelRenderer() override;
  EglSurfelRenderer(const EglSurfelRenderer&) = delete;
  EglSurfelRenderer& operator=(const EglSurfelRenderer&) = delete;

  [[nodiscard]] Status Render(const SurfelRenderInput& input,
                              const Eigen::Isometry3d& T_world_sensor,
                              VertexNormalMap* out) override;
  /// "egl (<GL_RENDERER>)".
  std::string Name() const override;
  const RangeProjection& projection() const override;

  /// GL_RENDERER / GL_VERSION strings and which EGL platform was used ("device", "surfaceless",
  /// "default").
  const std::string& gl_renderer() const;
  const std::string& gl_version() const;
  const std::string& egl_platform() const;
  /// True for Mesa's software rasterisers (llvmpipe, softpipe, swrast).
  bool IsSoftware() const;

 private:
  struct Impl;
  explicit EglSurfelRenderer(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

}  // namespace slam_mms
