#include "render_egl/egl_context.hpp"

#include <EGL/eglext.h>
#define GL_GLEXT_PROTOTYPES 1
#include <GL/glcorearb.h>

#include <cstring>
#include <sstream>
#include <vector>

namespace slam_mms::internal {
namespace {

bool HasExtension(const char* list, const char* name) {
  if (list == nullptr) return false;
  const size_t n = std::strlen(name);
  for (const char* p = list; (p = std::strstr(p, name)) != nullptr; p += n) {
    if ((p == list || p[-1] == ' ') && (p[n] == ' ' || p[n] == '\0')) return true;
  }
  return false;
}

std::string EglErrorString(EGLint e) {
  std::ostringstream os;
  os << "EGL error 0x" << std::hex << e;
  return os.str();
}

// Initialises `display` and creates a current core context on it; false with *why on failure.
bool TryDisplay(EGLDisplay display, EglContext* out, std::string* why) {
  if (display == EGL_NO_DISPLAY) {
    *why = "no display";
    return false;
  }
  EGLint major = 0, minor = 0;
  if (!eglInitialize(display, &major, &minor)) {
    *why = "eglInitialize failed (" + EglErrorString(eglGetError()) + ")";
    return false;
  }
  const char* exts = eglQueryString(display, EGL_EXTENSIONS);
  if (!HasExtension(exts, "EGL_KHR_surfaceless_context")) {
    *why = "EGL_KHR_surfaceless_context not supported";
    return false;
  }
  if (!eglBindAPI(EGL_OPENGL_API)) {
    *why = "eglBindAPI(EGL_OPENGL_API) failed";
    return false;
  }
  EGLConfig config = nullptr;
  bool have_config = false;
  if (HasExtension(exts, "EGL_KHR_no_config_context")) {
    config = static_cast<EGLConfig>(nullptr);  // EGL_NO_CONFIG_KHR
    have_config = true;
  } else {
    const EGLint surface_types[] = {EGL_PBUFFER_BIT, 0};
    for (EGLint st : surface_types) {
      const EGLint attribs[] = {EGL_SURFACE_TYPE, st, EGL_RENDERABLE_TYPE, EGL_OPENGL_BIT,
                                EGL_NONE};
      EGLint n = 0;
      if (eglChooseConfig(display, attribs, &config, 1, &n) && n > 0) {
        have_config = true;
        break;
      }
    }
  }
  if (!have_config) {
    *why = "no EGL config with EGL_OPENGL_BIT";
    return false;
  }
  const EGLint versions[][2] = {{4, 5}, {3, 3}};
  for (const auto& v : versions) {
    const EGLint attribs[] = {EGL_CONTEXT_MAJOR_VERSION,
                              v[0],
                              EGL_CONTEXT_MINOR_VERSION,
                              v[1],
                              EGL_CONTEXT_OPENGL_PROFILE_MASK,
                              EGL_CONTEXT_OPENGL_CORE_PROFILE_BIT,
                              EGL_NONE};
    EGLContext ctx = eglCreateContext(display, config, EGL_NO_CONTEXT, attribs);
    if (ctx == EGL_NO_CONTEXT) continue;
    if (!eglMakeCurrent(display, EGL_NO_SURFACE, EGL_NO_SURFACE, ctx)) {
      eglDestroyContext(display, ctx);
      continue;
    }
    out->display = display;
    out->context = ctx;
    const GLubyte* r = glGetString(GL_RENDERER);
    const GLubyte* ver = glGetString(GL_VERSION);
    out->gl_renderer = r != nullptr ? reinterpret_cast<const char*>(r) : "unknown";
    out->gl_version = ver != nullptr ? reinterpret_cast<const char*>(ver) : "unknown";
    return true;
  }
  *why = "no OpenGL 4.5 or 3.3 core context (" + EglErrorString(eglGetError()) + ")";
  return false;
}

}  // namespace

Status EglContext::Open() {
  std::vector<std::string> tried;
  auto get_platform_display = reinterpret_cast<PFNEGLGETPLATFORMDISPLAYEXTPROC>(
      eglGetProcAddress("eglGetPlatformDisplayEXT"));
  auto query_devices =
      reinterpret_cast<PFNEGLQUERYDEVICESEXTPROC>(eglGetProcAddress("eglQueryDevicesEXT"));
  auto query_device_string = reinterpret_cast<PFNEGLQUERYDEVICESTRINGEXTPROC>(
      eglGetProcAddress("eglQueryDeviceStringEXT"));
  const char* client_exts = eglQueryString(EGL_NO_DISPLAY, EGL_EXTENSIONS);
  std::string why;

  std::vector<EGLDeviceEXT> hardware, software;
  if (get_platform_display != nullptr && query_devices != nullptr &&
      HasExtension(client_exts, "EGL_EXT_platform_device")) {
    EGLDeviceEXT devices[16];
    EGLint n = 0;
    if (query_devices(16, devices, &n)) {
      for (EGLint i = 0; i < n; ++i) {
        const char* dev_exts = query_device_string != nullptr
                                   ? query_device_string(devices[i], EGL_EXTENSIONS)
                                   : nullptr;
        (HasExtension(dev_exts, "EGL_MESA_device_software") ? software : hardware)
            .push_back(devices[i]);
      }
    }
  }
  for (EGLDeviceEXT dev : hardware) {
    if (TryDisplay(get_platform_display(EGL_PLATFORM_DEVICE_EXT, dev, nullptr), this, &why)) {
      platform = "device";
      return OkStatus();
    }
    tried.push_back("device: " + why);
  }
  if (get_platform_display != nullptr &&
      HasExtension(client_exts, "EGL_MESA_platform_surfaceless")) {
    if (TryDisplay(
            get_platform_display(EGL_PLATFORM_SURFACELESS_MESA, EGL_DEFAULT_DISPLAY, nullptr), this,
            &why)) {
      platform = "surfaceless";
      return OkStatus();
    }
    tried.push_back("surfaceless: " + why);
  }
  if (TryDisplay(eglGetDisplay(EGL_DEFAULT_DISPLAY), this, &why)) {
    platform = "default";
    return OkStatus();
  }
  tried.push_back("default display: " + why);
  for (EGLDeviceEXT dev : software) {
    if (TryDisplay(get_platform_display(EGL_PLATFORM_DEVICE_EXT, dev, nullptr), this, &why)) {
      platform = "device";
      return OkStatus();
    }
    tried.push_back("software device: " + why);
  }
  std::string msg = "EglSurfelRenderer: no headless EGL/OpenGL context could be created (tried ";
  for (size_t i = 0; i < tried.size(); ++i) msg += (i ? "; " : "") + tried[i];
  return UnavailableError(msg + ")");
}

Status EglContext::MakeCurrent() const {
  if (context == EGL_NO_CONTEXT) return FailedPreconditionError("EGL context is not open");
  if (eglGetCurrentContext() == context) return OkStatus();
  if (!eglMakeCurrent(display, EGL_NO_SURFACE, EGL_NO_SURFACE, context)) {
    return UnavailableError("eglMakeCurrent failed (" + EglErrorString(eglGetError()) +
                            "); is the context current on another thread?");
  }
  return OkStatus();
}

void EglContext::Close() {
  if (context != EGL_NO_CONTEXT) {
    if (eglGetCurrentContext() == context) {
      eglMakeCurrent(display, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
    }
    eglDestroyContext(display, context);
    context = EGL_NO_CONTEXT;
  }
}

}  // namespace slam_mms::internal
