#pragma once
// Headless EGL + OpenGL core context creation (private to render_egl).
#include <EGL/egl.h>

#include <string>

#include "slam_mms/core/status.hpp"

namespace slam_mms::internal {

struct EglContext {
  EGLDisplay display = EGL_NO_DISPLAY;
  EGLContext context = EGL_NO_CONTEXT;
  std::string platform;  // "device", "surfaceless" or "default"
  std::string gl_renderer;
  std::string gl_version;

  /// Tries hardware EGL devices, then Mesa surfaceless, then the default display, then software
  /// devices; OpenGL 4.5 core, else 3.3 core. Leaves the context current on success.
  Status Open();
  /// Makes the context current on the calling thread.
  Status MakeCurrent() const;
  /// Releases the context (the display stays initialised: EGL displays are process-wide and may be
  /// shared with other renderers).
  void Close();
};

}  // namespace slam_mms::internal
