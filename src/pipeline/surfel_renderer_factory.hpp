#pragma once
// MakeSurfelRenderer: the automatic choice between EglSurfelRenderer and CpuSurfelRenderer.
//   kAuto: EGL when it starts on a hardware GPU (GL_RENDERER not llvmpipe/softpipe/swrast);
//          otherwise the CPU renderer, which is faster than Mesa's software rasteriser (measured
//          in benchmarks/bm_render.cpp: BM_RenderCpu vs BM_RenderEgl). The first kAuto call that
//          finds no hardware renderer is remembered for the process: later kAuto calls return
//          the CPU renderer without probing EGL again (a probe costs about 0.15 s). On Linux
//          a machine without any GPU device node (/dev/dri/renderD*, /dev/nvidia*, /dev/dxg)
//          is not probed at all.
//   kCpu / kEgl: that one (kEgl returns EGL's Unavailable status when it cannot start, and
//   Unavailable in a build without the render_egl module, SLAM_MMS_WITH_EGL=OFF, where kAuto is
//   always the CPU renderer).
//
// num_threads: the renderer's host threads (the calling thread included): the CPU renderer's
// cull and raster, the EGL renderer's surfel gather and image unpack.
// Thread safety: the function is thread-safe; the renderer it returns is not (see each class).

#include <memory>

#include "slam_mms/core/status.hpp"
#include "slam_mms/surfel/surfel_renderer.hpp"

namespace slam_mms {

StatusOr<std::unique_ptr<SurfelRenderer>> MakeSurfelRenderer(
    const SurfelRendererOptions& options,
    SurfelRendererBackend backend = SurfelRendererBackend::kAuto, int num_threads = 2);

}  // namespace slam_mms
