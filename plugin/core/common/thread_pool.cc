#include "common/thread_pool.h"

#include <unistd.h>

#include <algorithm>
#include <chrono>

namespace mjtouch {
namespace {

// Workers spin this long after a job before sleeping: steps come every
// ~0.1-1 ms, and a sleeping worker takes ~10-50 us to wake.
constexpr auto kSpin = std::chrono::microseconds(50);

inline void CpuRelax() {
#if defined(__x86_64__) || defined(__i386__)
  __builtin_ia32_pause();
#elif defined(__aarch64__)
  __asm__ __volatile__("yield");  // the spin-wait hint of ARMv8
#endif
}

// A waiting thread yields after a short spin: on a machine busier than
// its cores, the thread it waits for may share its core.
inline void Backoff(int k) {
  if (k < 64)
    CpuRelax();
  else
    std::this_thread::yield();
}

}  // namespace

ThreadPool& ThreadPool::Shared() {
  // Never destroyed: workers may still sleep at exit, and a pool inherited
  // by a forked child (Ray, multiprocessing) is not used (see Run).
  static ThreadPool* pool = new ThreadPool();
  return *pool;
}

ThreadPool::~ThreadPool() {
  {
    std::lock_guard<std::mutex> lk(wake_mutex_);
    stop_ = true;
  }
  wake_.notify_all();
  for (auto& t : threads_) t.join();
}

int ThreadPool::workers() const {
  std::lock_guard<std::mutex> lk(wake_mutex_);
  return static_cast<int>(threads_.size());
}

void ThreadPool::EnsureWorkers(int count) {
  std::lock_guard<std::mutex> lk(wake_mutex_);
  if (threads_.empty() && count > 0) workers_pid_ = static_cast<int>(getpid());
  while (static_cast<int>(threads_.size()) < count) {
    const int index = static_cast<int>(threads_.size());
    threads_.emplace_back([this, index] { WorkerLoop(index); });
  }
}

void ThreadPool::RunChunks() {
  for (int k = next_chunk_.fetch_add(1); k < num_chunks_; k = next_chunk_.fetch_add(1)) {
    (*fn_)(k);
    done_chunks_.fetch_add(1);
  }
}

void ThreadPool::WorkerLoop(int /*index*/) {
  uint64_t seen = generation_.load();
  while (true) {
    uint64_t g = generation_.load();
    if (g == seen && !stop_) {
      const auto until = std::chrono::steady_clock::now() + kSpin;
      int k = 0;
      // Spin politely: pause, and yield every few, so that a worker sharing
      // a core with the caller (another process holds the other) does not
      // take the caller's time slice.
      while ((g = generation_.load()) == seen && !stop_) {
        CpuRelax();
        if (++k % 16 == 0) {
          if (std::chrono::steady_clock::now() > until) break;
          std::this_thread::yield();
        }
      }
      if (g == seen && !stop_) {
        std::unique_lock<std::mutex> lk(wake_mutex_);
        wake_.wait(lk, [&] { return generation_.load() != seen || stop_; });
        g = generation_.load();
      }
    }
    if (stop_) return;
    seen = g;
    // Announce, then check the job is still g: the caller closes a job and
    // waits for helpers_active_ == 0 before it frees it (both seq_cst, so
    // either it sees this helper or the helper sees the job closed).
    helpers_active_.fetch_add(1);
    if (generation_.load() == g && job_open_.load() &&
        helpers_joined_.fetch_add(1) < helpers_wanted_)
      RunChunks();
    helpers_active_.fetch_sub(1);
  }
}

void ThreadPool::Run(int num_chunks, int threads, const std::function<void(int)>& fn) {
  // A forked child inherits the pool but not its workers: it runs serially.
  const int pid = workers_pid_.load();
  const bool parallel =
      threads > 1 && num_chunks > 1 && (pid == 0 || pid == static_cast<int>(getpid()));
  std::unique_lock<std::mutex> job(job_mutex_, std::defer_lock);
  if (!parallel || !job.try_lock()) {
    // Serial, or the pool is busy with another caller: run every chunk here.
    for (int k = 0; k < num_chunks; ++k) fn(k);
    return;
  }
  const int helpers = std::min(std::min(threads, kMaxThreads), num_chunks) - 1;
  EnsureWorkers(helpers);
  fn_ = &fn;
  num_chunks_ = num_chunks;
  helpers_wanted_ = helpers;
  next_chunk_ = 0;
  done_chunks_ = 0;
  helpers_joined_ = 0;
  job_open_ = true;
  {
    std::lock_guard<std::mutex> lk(wake_mutex_);
    generation_.fetch_add(1);
  }
  wake_.notify_all();
  RunChunks();
  // Wait for chunks that workers hold: spin briefly, then yield, so that a
  // worker descheduled on a busy machine gets the core back.
  for (int k = 0; done_chunks_.load() < num_chunks; ++k) Backoff(k);
  job_open_ = false;
  for (int k = 0; helpers_active_.load() > 0; ++k) Backoff(k);
  fn_ = nullptr;
}

}  // namespace mjtouch
