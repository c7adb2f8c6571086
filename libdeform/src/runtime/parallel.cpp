#include "deform/runtime/parallel.hpp"
#include <algorithm>

namespace deform {

ThreadPool::ThreadPool(unsigned threads) {
  if (threads == 0) threads = std::max(1u, std::thread::hardware_concurrency());
  workers_.reserve(threads - 1);
  for (unsigned i = 1; i < threads; ++i) workers_.emplace_back([this, i] { worker_loop(i); });
}

ThreadPool::~ThreadPool() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stop_ = true;
  }
  wake_.notify_all();
  for (std::thread& t : workers_) t.join();
}

void ThreadPool::parallel_for(std::size_t count, std::size_t min_chunk,
                              const std::function<void(std::size_t, std::size_t)>& fn) {
  if (count == 0) return;
  min_chunk = std::max<std::size_t>(1, min_chunk);
  const std::size_t max_chunks = (count + min_chunk - 1) / min_chunk;
  const std::size_t chunks = std::min<std::size_t>(size(), max_chunks);
  if (chunks <= 1) {
    fn(0, count);
    return;
  }
  const std::size_t chunk = (count + chunks - 1) / chunks;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    task_ = &fn;
    count_ = count;
    chunk_ = chunk;
    pending_ = static_cast<unsigned>(workers_.size());
    ++generation_;
  }
  wake_.notify_all();
  fn(0, std::min(chunk, count));
  std::unique_lock<std::mutex> lock(mutex_);
  done_.wait(lock, [this] { return pending_ == 0; });
  task_ = nullptr;
}

void ThreadPool::worker_loop(unsigned index) {
  unsigned seen = 0;
  for (;;) {
    const std::function<void(std::size_t, std::size_t)>* task;
    std::size_t begin, end;
    {
      std::unique_lock<std::mutex> lock(mutex_);
      wake_.wait(lock, [&] { return stop_ || generation_ != seen; });
      if (stop_) return;
      seen = generation_;
      task = task_;
      begin = std::min(count_, chunk_ * index);
      end = std::min(count_, begin + chunk_);
    }
    if (begin < end) (*task)(begin, end);
    {
      std::lock_guard<std::mutex> lock(mutex_);
      if (--pending_ == 0) done_.notify_one();
    }
  }
}

}  // namespace deform
