#pragma once
// WorkerPool: a tiny fork-join pool of persistent threads, so ICP iterations do not create threads.
// Run(fn) calls fn(i) for i in [0, size()) concurrently, the caller taking i = 0, and returns when
// all calls are done. No allocation per Run.
//
// Thread safety: Run must not be called concurrently on the same pool.

#include <condition_variable>
#include <cstdint>
#include <mutex>
#include <thread>
#include <vector>

namespace slam_mms::registration_internal {

class WorkerPool {
 public:
  /// num_threads >= 1 is the total parallelism including the calling thread.
  explicit WorkerPool(int num_threads);
  ~WorkerPool();
  WorkerPool(const WorkerPool&) = delete;
  WorkerPool& operator=(const WorkerPool&) = delete;

  int size() const { return static_cast<int>(threads_.size()) + 1; }

  template <typename F>
  void Run(F& fn) {
    RunImpl(&Thunk<F>, &fn);
  }

  /// [begin, end) of chunk i of n items split into size() near-equal parts.
  void Range(int i, size_t n, size_t* begin, size_t* end) const {
    const size_t k = static_cast<size_t>(size());
    *begin = n * static_cast<size_t>(i) / k;
    *end = n * static_cast<size_t>(i + 1) / k;
  }

 private:
  using Fn = void (*)(void*, int);
  template <typename F>
  static void Thunk(void* ctx, int i) {
    (*static_cast<F*>(ctx))(i);
  }
  void RunImpl(Fn fn, void* ctx);
  void WorkerLoop(int index);

  std::vector<std::thread> threads_;
  std::mutex mutex_;
  std::condition_variable start_cv_;
  std::condition_variable done_cv_;
  Fn fn_ = nullptr;
  void* ctx_ = nullptr;
  uint64_t generation_ = 0;
  int pending_ = 0;
  bool stop_ = false;
};

}  // namespace slam_mms::registration_internal
