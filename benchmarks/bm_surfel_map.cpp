// SurfelMap memory bounding (issue 9): the cost of dropping a submap and of compacting the slot
// storage on a map of N street surfels spread over 20 submaps, and the memory each gives back.
//
// BM_SurfelMapRemoveSubmap/<N>: RemoveSubmap of one submap (N / 20 surfels; its slots are freed for
// reuse), timed; the submap is added back untimed so every iteration removes the same amount.
// BM_SurfelMapCompact/<N>: RemoveSubmapsExcept of all but the 4 newest submaps (untimed), then
// Compact(), timed. Counters: bytes_before / bytes_after (SurfelMap::MemoryBytes around Compact).
#include <benchmark/benchmark.h>

#include <vector>

#include "slam_mms/surfel/surfel_map.hpp"
#include "surfel/synthetic_surfels.hpp"

namespace {

constexpr int kSubmaps = 20;

std::vector<slam_mms::Surfel> SurfelsInSubmaps(size_t n) {
  std::vector<slam_mms::Surfel> s = slam_mms::internal::MakeStreetSurfels(n, 3, 200.0f);
  for (size_t k = 0; k < s.size(); ++k) {
    s[k].submap_id = static_cast<int32_t>(k * kSubmaps / s.size());  // contiguous along the build
  }
  return s;
}

void BM_SurfelMapRemoveSubmap(benchmark::State& state) {
  const std::vector<slam_mms::Surfel> all = SurfelsInSubmaps(static_cast<size_t>(state.range(0)));
  slam_mms::SurfelMap map;
  if (!map.AddSurfels(all).ok()) state.SkipWithError("AddSurfels failed");
  std::vector<slam_mms::Surfel> removed;
  size_t n = 0;
  for (auto _ : state) {
    removed.clear();
    n = map.RemoveSubmap(7, &removed);
    state.PauseTiming();
    if (!map.AddSurfels(removed).ok()) state.SkipWithError("AddSurfels failed");
    state.ResumeTiming();
  }
  state.counters["removed"] = static_cast<double>(n);
}
BENCHMARK(BM_SurfelMapRemoveSubmap)->Arg(1000000)->Unit(benchmark::kMillisecond);

void BM_SurfelMapCompact(benchmark::State& state) {
  const std::vector<slam_mms::Surfel> all = SurfelsInSubmaps(static_cast<size_t>(state.range(0)));
  size_t before = 0, after = 0;
  for (auto _ : state) {
    state.PauseTiming();
    slam_mms::SurfelMap map;
    if (!map.AddSurfels(all).ok()) state.SkipWithError("AddSurfels failed");
    map.RemoveSubmapsExcept({16, 17, 18, 19});
    before = map.MemoryBytes();
    state.ResumeTiming();
    map.Compact();
    state.PauseTiming();
    after = map.MemoryBytes();
    state.ResumeTiming();
  }
  state.counters["bytes_before"] = static_cast<double>(before);
  state.counters["bytes_after"] = static_cast<double>(after);
}
// A fixed iteration count: each iteration rebuilds the 1M-surfel map (untimed, but slow).
BENCHMARK(BM_SurfelMapCompact)->Arg(1000000)->Iterations(3)->Unit(benchmark::kMillisecond);

}  // namespace
