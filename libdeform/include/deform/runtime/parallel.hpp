#pragma once
// A small persistent thread pool for splitting a per-frame job's range across cores, and run_parallel(), which splits
// any libdeform job with it.
//
// Every libdeform job has count() elements and run(begin, end) over a range of them that touches nothing outside it,
// so an engine with its own job system splits the range itself and never needs this. ThreadPool is the convenience
// for everyone else: threads are created once (construction), then parallel_for() hands each worker one contiguous
// chunk and waits. parallel_for() allocates nothing; it synchronises through one mutex and condition variable per call
// (not per element).
#include <algorithm>
#include <condition_variable>
#include <cstddef>
#include <functional>
#include <mutex>
#include <thread>
#include <vector>

#include "deform/runtime/error.hpp"
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

// Runs job.run(begin, end) over [0, job.count()) split across the pool's threads, in chunks of at least `min_chunk`
// elements (small jobs stay on the calling thread) cut at multiples of Job::split_multiple (so that no two threads
// write the same cache line). The job's O(1) checks run first, as job.run(0, 0): when they refuse, that Status is
// returned and nothing is written. Each job of libdeform gives every element the same bits wherever its range begins,
// so the result is bit-identical to job.run(). Allocates nothing. For SkinningJob, LatticeEvaluateJob,
// VertexNormalsJob and BlendingJob; Job::min_parallel_chunk is the default chunk, below which a thread wake-up costs
// more than it saves (measured per job; estimated for BlendingJob, see blending.hpp).
template <class Job>
Status run_parallel(const Job& job, ThreadPool& pool, std::size_t min_chunk = Job::min_parallel_chunk) {
  if (const Status checked = job.run(0, 0); !checked) return checked;
  struct Split {
    const Job* job;
    std::size_t count;
  };
  constexpr std::size_t multiple = Job::split_multiple;
  const Split split{&job, job.count()};
  const Split* context = &split;  // one pointer: the std::function below stores it without allocating
  const std::size_t units = (split.count + multiple - 1) / multiple;
  pool.parallel_for(units, (min_chunk + multiple - 1) / multiple, [context](std::size_t begin, std::size_t end) {
    (void)context->job->run(begin * multiple, std::min(end * multiple, context->count));
  });
  return {};
}

}  // namespace deform
