#pragma once
// A small persistent thread pool for splitting a per-frame job's range across cores.
//
// Every libdeform job works on a range [begin, end) of its elements and touches nothing outside it, so an engine with
// its own job system splits the range itself and never needs this. ThreadPool is the convenience for everyone else:
// threads are created once (construction), then parallel_for() hands each worker one contiguous chunk and waits.
// parallel_for() allocates nothing; it synchronises through one mutex and condition variable per call (not per element).
#include <condition_variable>
#include <cstddef>
#include <functional>
#include <mutex>
#include <thread>
#include <vector>

#include "deform/runtime/export.hpp"
namespace deform {

class DEFORM_RUNTIME_API ThreadPool {
 public:
  // `threads` = total workers including the calling thread; 0 means std::thread::hardware_concurrency().
  explicit ThreadPool(unsigned threads = 0);
  ~ThreadPool();
  ThreadPool(const ThreadPool&) = delete;
  ThreadPool& operator=(const ThreadPool&) = delete;

  // Number of threads that share work, including the caller.
  unsigned size() const noexcept { return static_cast<unsigned>(workers_.size()) + 1; }

  // Calls fn(begin, end) on disjoint chunks covering [0, count), at most size() of them, each at least `min_chunk`
  // long (except a last short one), the caller running the first; returns when all are done. Not reentrant: one
  // parallel_for at a time per pool. `fn` must not throw.
  void parallel_for(std::size_t count, std::size_t min_chunk,
                    const std::function<void(std::size_t begin, std::size_t end)>& fn);

 private:
  void worker_loop(unsigned index);

  std::vector<std::thread> workers_;
  std::mutex mutex_;
  std::condition_variable wake_;
  std::condition_variable done_;
  const std::function<void(std::size_t, std::size_t)>* task_ = nullptr;
  std::size_t count_ = 0;
  std::size_t chunk_ = 0;
  unsigned generation_ = 0;
  unsigned pending_ = 0;
  bool stop_ = false;
};

}  // namespace deform
