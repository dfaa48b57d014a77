#pragma once
// CpuSurfelRenderer: the native SurfelRenderer. A z-buffer splat of oriented discs, exact per pixel
// centre ray (see surfel_renderer.hpp for the image definition it shares with EglSurfelRenderer).
//
// How: pass 1 splits the surfels into num_threads contiguous chunks of draw positions; each thread
// culls its chunk (range, facing), bounds each disc in pixel space (its linearised projection, or
// the cone around it for large discs) and appends a record per 128-column bin the box touches.
// Pass 2: the threads take the bins in turn; a bin's records are rastered in draw order into its
// slice of one depth/winner buffer (exact ray-disc test per pixel centre; nearest wins, ties to the
// earlier surfel) and its output pixels are written while still in cache. Bins are disjoint, so the
// image does not depend on the number of threads. Worker threads are persistent and all buffers
// are reused, so a steady-state Render does not allocate.
//
// Thread safety: not thread-safe; one renderer per thread. Move-only.

#include <memory>
#include <string>

#include "slam_mms/surfel/surfel_renderer.hpp"

namespace slam_mms {

class CpuSurfelRenderer final : public SurfelRenderer {
 public:
  /// Default options (64 x 2048 HDL-64 image, 2 threads).
  CpuSurfelRenderer();
  /// Returns InvalidArgument when options.Validate() fails or num_threads (the calling thread
  /// included) is outside [1, 64].
  static StatusOr<std::unique_ptr<CpuSurfelRenderer>> Create(const SurfelRendererOptions& options,
                                                             int num_threads = 2);
  ~CpuSurfelRenderer() override;
  CpuSurfelRenderer(CpuSurfelRenderer&&) noexcept;
  CpuSurfelRenderer& operator=(CpuSurfelRenderer&&) noexcept;
  CpuSurfelRenderer(const CpuSurfelRenderer&) = delete;
  CpuSurfelRenderer& operator=(const CpuSurfelRenderer&) = delete;

  [[nodiscard]] Status Render(const SurfelRenderInput& input,
                              const Eigen::Isometry3d& T_world_sensor,
                              VertexNormalMap* out) override;
  std::string Name() const override { return "cpu"; }
  const RangeProjection& projection() const override;
  const SurfelRendererOptions& options() const;

 private:
  struct Impl;
  explicit CpuSurfelRenderer(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

}  // namespace slam_mms
