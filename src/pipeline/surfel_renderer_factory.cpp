#include "pipeline/surfel_renderer_factory.hpp"

#include <filesystem>
#include <mutex>
#include <string>
#include <utility>

#include "slam_mms/core/logging.hpp"
#include "surfel/cpu_surfel_renderer.hpp"
#if SLAM_MMS_HAVE_EGL
#include "render_egl/egl_surfel_renderer.hpp"
#endif

namespace slam_mms {

#if SLAM_MMS_HAVE_EGL
namespace {

// kAuto's answer where EGL gave no hardware renderer: probing costs a Mesa load, a context and a
// shader build (about 0.15 s, per MappingSystem), and the answer does not change within a
// process, so later kAuto calls go to the CPU renderer at once (with the first probe's reason).
std::mutex g_auto_mutex;
bool g_auto_is_cpu = false;
std::string g_auto_reason;

// Linux: no GPU device node at all (DRM render nodes, NVIDIA's, WSL's) means EGL can only run
// on the software rasteriser, which kAuto does not use; the probe is skipped then.
bool NoGpuDeviceNode(std::string* reason) {
#if defined(__linux__)
  std::error_code ec;
  for (const char* node : {"/dev/nvidiactl", "/dev/nvidia0", "/dev/dxg"}) {
    if (std::filesystem::exists(node, ec)) return false;
  }
  for (const auto& entry : std::filesystem::directory_iterator("/dev/dri", ec)) {
    if (entry.path().filename().string().rfind("renderD", 0) == 0) return false;
  }
  *reason = "no GPU device node (/dev/dri/renderD*, /dev/nvidia*, /dev/dxg)";
  return true;
#else
  (void)reason;
  return false;
#endif
}

}  // namespace
#endif  // SLAM_MMS_HAVE_EGL

StatusOr<std::unique_ptr<SurfelRenderer>> MakeSurfelRenderer(const SurfelRendererOptions& options,
                                                             SurfelRendererBackend backend,
                                                             int num_threads) {
  SLAM_MMS_RETURN_IF_ERROR(options.Validate());
#if !SLAM_MMS_HAVE_EGL
  if (backend == SurfelRendererBackend::kEgl) {
    return UnavailableError("MakeSurfelRenderer: EGL was not built (SLAM_MMS_WITH_EGL=OFF)");
  }
  SLAM_MMS_ASSIGN_OR_RETURN(auto cpu_only, CpuSurfelRenderer::Create(options, num_threads));
  return std::unique_ptr<SurfelRenderer>(std::move(cpu_only));
#else
  if (backend == SurfelRendererBackend::kAuto) {
    std::lock_guard<std::mutex> lock(g_auto_mutex);
    if (!g_auto_is_cpu && NoGpuDeviceNode(&g_auto_reason)) g_auto_is_cpu = true;
    if (g_auto_is_cpu) {
      SLAM_MMS_LOG(kInfo) << "surfel renderer: cpu (" << g_auto_reason << ")";
      SLAM_MMS_ASSIGN_OR_RETURN(auto cpu, CpuSurfelRenderer::Create(options, num_threads));
      return std::unique_ptr<SurfelRenderer>(std::move(cpu));
    }
  }
  if (backend == SurfelRendererBackend::kEgl || backend == SurfelRendererBackend::kAuto) {
    auto egl = EglSurfelRenderer::Create(options, num_threads);
    if (backend == SurfelRendererBackend::kEgl) {
      if (!egl.ok()) return egl.status();
      return std::unique_ptr<SurfelRenderer>(std::move(egl).value());
    }
    if (egl.ok() && !(*egl)->IsSoftware()) {
      SLAM_MMS_LOG(kInfo) << "surfel renderer: " << (*egl)->Name() << " via EGL "
                          << (*egl)->egl_platform();
      return std::unique_ptr<SurfelRenderer>(std::move(egl).value());
    }
    std::string reason = egl.ok() ? "EGL runs on the software rasteriser " + (*egl)->gl_renderer() +
                                        ", which is slower"
                                  : egl.status().message();
    SLAM_MMS_LOG(kInfo) << "surfel renderer: cpu (" << reason << ")";
    std::lock_guard<std::mutex> lock(g_auto_mutex);
    g_auto_is_cpu = true;
    g_auto_reason = std::move(reason);
  }
  SLAM_MMS_ASSIGN_OR_RETURN(auto cpu, CpuSurfelRenderer::Create(options, num_threads));
  return std::unique_ptr<SurfelRenderer>(std::move(cpu));
#endif
}

}  // namespace slam_mms
