#pragma once
// WorkerPool: a fixed set of persistent threads that run one task per thread and join at a barrier.
// Used by the CPU renderer and the surfel map so that per-frame work does not spawn threads.
// Thread safety: Run must be called from one thread at a time.

#include <condition_variable>
#include <mutex>
#include <thread>
#include <type_traits>
#include <vector>

namespace slam_mms::internal {

class WorkerPool {
 public:
  /// `num_threads` >= 1 counts the calling thread: num_threads - 1 workers are started.
  explicit WorkerPool(int num_threads);
  ~WorkerPool();
  WorkerPool(const WorkerPool&) = delete;
  WorkerPool& operator=(const WorkerPool&) = delete;

  int num_threads() const { return static_cast<int>(workers_.size()) + 1; }
  /// Runs fn(0) on the calling thread and fn(i) on worker i (1..n-1); returns when all are done.
  /// Takes any callable by reference (no std::function, so no per-call allocation).
  template <typename Fn>
  void Run(Fn&& fn) {
    RunImpl([](void* ctx, int i) { (*static_cast<std::remove_reference_t<Fn>*>(ctx))(i); },
            const_cast<void*>(static_cast<const void*>(&fn)));
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
  long long generation_ = 0;
  int pending_ = 0;
  bool stop_ = false;
};

}  // namespace slam_mms::internal
