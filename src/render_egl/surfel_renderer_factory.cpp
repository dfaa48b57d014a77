#include "slam_mms/render_egl/surfel_renderer_factory.hpp"

#include <utility>

#include "slam_mms/core/logging.hpp"
#include "slam_mms/render_egl/egl_surfel_renderer.hpp"
#include "slam_mms/surfel/cpu_surfel_renderer.hpp"

namespace slam_mms {

const char* SurfelRendererBackendName(SurfelRendererBackend backend) {
  switch (backend) {
    case SurfelRendererBackend::kAuto: return "auto";
    case SurfelRendererBackend::kCpu: return "cpu";
    case SurfelRendererBackend::kEgl: return "egl";
  }
  return "unknown";
}

StatusOr<std::unique_ptr<SurfelRenderer>> MakeSurfelRenderer(const SurfelRendererOptions& options,
                                                             SurfelRendererBackend backend) {
  SLAM_MMS_RETURN_IF_ERROR(options.Validate());
  if (backend == SurfelRendererBackend::kEgl || backend == SurfelRendererBackend::kAuto) {
    auto egl = EglSurfelRenderer::Create(options);
    if (backend == SurfelRendererBackend::kEgl) {
      if (!egl.ok()) return egl.status();
      return std::unique_ptr<SurfelRenderer>(std::move(egl).value());
    }
    if (egl.ok() && !(*egl)->IsSoftware()) {
      SLAM_MMS_LOG(kInfo) << "surfel renderer: " << (*egl)->Name() << " via EGL "
                          << (*egl)->egl_platform();
      return std::unique_ptr<SurfelRenderer>(std::move(egl).value());
    }
    if (egl.ok()) {
      SLAM_MMS_LOG(kInfo) << "surfel renderer: cpu (EGL runs on the software rasteriser "
                          << (*egl)->gl_renderer() << ", which is slower)";
    } else {
      SLAM_MMS_LOG(kInfo) << "surfel renderer: cpu (" << egl.status().message() << ")";
    }
  }
  SLAM_MMS_ASSIGN_OR_RETURN(auto cpu, CpuSurfelRenderer::Create(options));
  return std::unique_ptr<SurfelRenderer>(std::move(cpu));
}

}  // namespace slam_mms
