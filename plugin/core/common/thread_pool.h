// A persistent pool of worker threads shared by every caller in the process,
// for work split into fixed chunks. Outputs are bit-identical for any thread
// count as long as each chunk writes its own outputs and its arithmetic does
// not depend on which thread runs it (the caller's duty: chunks fixed by the
// inputs, never by the thread count).
//
// Callers participate: Run() runs chunks on the calling thread too and
// returns when all are done. One job at a time holds the pool; a caller that
// finds it busy (another simulation thread, e.g. mujoco.rollout, or a nested
// call) runs all its chunks itself instead of waiting, so callers never
// block each other and the process runs at most (pool workers + callers)
// threads.
#ifndef MJTOUCH_COMMON_THREAD_POOL_H_
#define MJTOUCH_COMMON_THREAD_POOL_H_

#include <algorithm>
#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <functional>
#include <mutex>
#include <thread>
#include <vector>

namespace mjtouch {

class ThreadPool {
 public:
  // Largest thread count a caller may ask for (the `threads` attribute).
  static constexpr int kMaxThreads = 64;

  // The process-wide pool (created on first use, grown on demand).
  static ThreadPool& Shared();

  ~ThreadPool();

  // Calls fn(chunk) for chunk in [0, num_chunks), on the caller and up to
  // threads - 1 pool workers; returns when every call has returned. fn must
  // not throw. threads <= 1 or num_chunks <= 1: all on the caller.
  void Run(int num_chunks, int threads, const std::function<void(int)>& fn);

  // Workers started so far (diagnostics).
  int workers() const;

 private:
  ThreadPool() = default;
  void EnsureWorkers(int count);  // with job_mutex_ held
  void WorkerLoop(int index);
  void RunChunks();

  // The job, valid while job_mutex_ is held by its caller.
  std::mutex job_mutex_;
  const std::function<void(int)>* fn_ = nullptr;
  int num_chunks_ = 0;
  int helpers_wanted_ = 0;  // workers allowed to join this job
  std::atomic<int> next_chunk_{0};
  std::atomic<int> done_chunks_{0};
  std::atomic<int> helpers_joined_{0};
  std::atomic<int> helpers_active_{0};  // joined and not yet left
  std::atomic<bool> job_open_{false};
  std::atomic<int> workers_pid_{0};      // process that started the workers
  std::atomic<uint64_t> generation_{0};  // bumped per job: wakes the workers

  mutable std::mutex wake_mutex_;
  std::condition_variable wake_;
  std::vector<std::thread> threads_;
  std::atomic<bool> stop_{false};
};

// Calls fn(j0, j1) on consecutive row ranges [j0, j1) that cover [0, rows):
// min(threads, rows / min_rows) parts (at least one) of near-equal size, run
// on the caller and the shared pool. The parts follow the thread count, so
// fn's outputs must depend on each row alone (the same bits for any split).
template <typename F>
inline void ForRowParts(int rows, int threads, int min_rows, F&& fn) {
  const int parts = std::max(1, std::min(threads, rows / min_rows));
  if (parts == 1) {
    fn(0, rows);
    return;
  }
  ThreadPool::Shared().Run(parts, threads,
                           [&](int k) { fn(rows * k / parts, rows * (k + 1) / parts); });
}

}  // namespace mjtouch

#endif  // MJTOUCH_COMMON_THREAD_POOL_H_
