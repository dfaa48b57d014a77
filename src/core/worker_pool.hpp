#pragma once
// WorkerPool: a small fork-join pool of persistent threads, shared (privately) by the modules that
// parallelise per-frame loops (surfel map and CPU renderer, ICP), so that per-frame work neither
// spawns threads nor allocates. Run(fn) calls fn(i) for i in [0, num_threads()) concurrently, the
// calling thread taking i = 0, and returns when all calls are done. Private to the library
// (src/core; not installed).
//
// Thread safety: Run must not be called concurrently on the same pool (one caller thread at a
// time).

#include <condition_variable>
#include <cstddef>
#include <cstdint>
#include <mutex>
#include <thread>
#include <type_traits>
#include <vector>

namespace slam_mms::internal {

class WorkerPool {
 public:
  /// `num_threads` >= 1 counts the calling thread: num_threads - 1 workers are started (values
  /// below 1 are treated as 1).
  explicit WorkerPool(int num_threads);
  ~WorkerPool();
  WorkerPool(const WorkerPool&) = delete;
  WorkerPool& operator=(const WorkerPool&) = delete;

  /// Total parallelism, the calling thread included.
  int num_threads() const { return static_cast<int>(workers_.size()) + 1; }
  int size() const { return num_threads(); }

  /// Runs fn(0) on the calling thread and fn(i) on worker i (1..n-1); returns when all are done.
  /// Takes any callable by reference (no std::function, so no per-call allocation).
  template <typename Fn>
  void Run(Fn&& fn) {
    RunImpl([](void* ctx, int i) { (*static_cast<std::remove_reference_t<Fn>*>(ctx))(i); },
            const_cast<void*>(static_cast<const void*>(&fn)));
  }

  /// [begin, end) of part i when n items are split into num_threads() near-equal parts.
  void Range(int i, size_t n, size_t* begin, size_t* end) const {
    const size_t k = static_cast<size_t>(num_threads());
    *begin = n * static_cast<size_t>(i) / k;
    *end = n * static_cast<size_t>(i + 1) / k;
  }

 private:
  using Trampoline = void (*)(void*, int);
  void RunImpl(Trampoline fn, void* ctx);
  void WorkerLoop(int index);

  std::vector<std::thread> workers_;
  std::mutex mutex_;
  std::condition_variable start_cv_;
  std::condition_variable done_cv_;
  Trampoline task_ = nullptr;
  void* task_ctx_ = nullptr;
  uint64_t generation_ = 0;
  int pending_ = 0;
  bool stop_ = false;
};

}  // namespace slam_mms::internal
