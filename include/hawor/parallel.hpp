// hawor/parallel.hpp — a small fork–join thread pool for the library's data-parallel loops
// (the infiller network's rows, ...).
//
// ThreadPool(n) keeps n − 1 worker threads; run(tasks, f) calls f(i) for every i in [0, tasks),
// spread over the workers and the calling thread, and returns when all calls have returned.
// Tasks are taken in order from one atomic counter, so any task count works with any pool size.
// The first exception thrown by a task is rethrown by run() (after every task has finished or
// been skipped). Workers spin briefly before they sleep, so that the many short fork–joins of
// one network forward pass (two per layer) do not pay a wake-up each; a pool that is idle for
// longer sleeps on a condition variable and costs nothing.
//
// Where the platform has no threads (WebAssembly built without -pthread) every pool has size 1
// and run() is a plain loop. Thread-safety: run() may be called by one thread at a time.
#pragma once

#include <algorithm>
#include <atomic>
#include <condition_variable>
#include <exception>
#include <functional>
#include <mutex>
#include <thread>
#include <vector>

#if defined(__EMSCRIPTEN__) && !defined(__EMSCRIPTEN_PTHREADS__)
#define HAWOR_NO_THREADS 1
#endif

namespace hawor {

class ThreadPool {
 public:
  /// A pool of `threads` threads in all, the caller included: threads − 1 workers are started.
  /// threads ≤ 0 means std::thread::hardware_concurrency(). Always 1 without thread support.
  explicit ThreadPool(int threads = 1) {
#ifdef HAWOR_NO_THREADS
    (void)threads;
#else
    if (threads <= 0) threads = static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
    for (int i = 1; i < threads; ++i) workers_.emplace_back([this] { workerLoop(); });
#endif
  }
  ~ThreadPool() {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      stop_ = true;
      ++generation_;
    }
    wake_.notify_all();
    for (std::thread& t : workers_) t.join();
  }
  ThreadPool(const ThreadPool&) = delete;
  ThreadPool& operator=(const ThreadPool&) = delete;

  /// Threads that run tasks, the caller included.
  int size() const { return static_cast<int>(workers_.size()) + 1; }

  /// f(i) for i in [0, tasks); returns when all have run. Rethrows a task's exception.
  void run(int tasks, const std::function<void(int)>& f) {
    if (tasks <= 0) return;
    if (workers_.empty() || tasks == 1) {
      for (int i = 0; i < tasks; ++i) f(i);
      return;
    }
    {
      std::lock_guard<std::mutex> lock(mutex_);
      job_ = &f;
      tasks_ = tasks;
      next_.store(0, std::memory_order_relaxed);
      pending_.store(static_cast<int>(workers_.size()), std::memory_order_relaxed);
      error_ = nullptr;
      generation_.fetch_add(1, std::memory_order_release);
    }
    wake_.notify_all();
    work();
    // Wait until every worker has left this job (each decrements pending_ once).
    for (int spin = 0; pending_.load(std::memory_order_acquire) != 0; ++spin)
      if (spin > kSpins) std::this_thread::yield();
    job_ = nullptr;
    if (error_) std::rethrow_exception(error_);
  }

 private:
  static constexpr int kSpins = 1 << 14;

  // Takes tasks from the shared counter until none is left.
  void work() {
    for (;;) {
      const int i = next_.fetch_add(1, std::memory_order_relaxed);
      if (i >= tasks_) return;
      try {
        (*job_)(i);
      } catch (...) {
        std::lock_guard<std::mutex> lock(mutex_);
        if (!error_) error_ = std::current_exception();
        next_.store(tasks_, std::memory_order_relaxed);  // skip the tasks not yet started
      }
    }
  }

  void workerLoop() {
    unsigned seen = 0;
    for (;;) {
      // Spin a little for the next job, then sleep until one is posted.
      int spin = 0;
      while (generation_.load(std::memory_order_acquire) == seen && spin < kSpins) ++spin;
      if (generation_.load(std::memory_order_acquire) == seen) {
        std::unique_lock<std::mutex> lock(mutex_);
        wake_.wait(lock, [&] { return generation_.load(std::memory_order_acquire) != seen; });
      }
      {
        std::lock_guard<std::mutex> lock(mutex_);
        seen = generation_.load(std::memory_order_acquire);
        if (stop_) return;
      }
      work();
      pending_.fetch_sub(1, std::memory_order_acq_rel);
    }
  }

  std::vector<std::thread> workers_;
  std::mutex mutex_;
  std::condition_variable wake_;
  std::atomic<unsigned> generation_{0};
  std::atomic<int> next_{0};
  std::atomic<int> pending_{0};
  const std::function<void(int)>* job_ = nullptr;
  int tasks_ = 0;
  std::exception_ptr error_;
  bool stop_ = false;
};

}  // namespace hawor
