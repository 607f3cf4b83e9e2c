// The engine's own job system, as small as one can be: a fixed set of worker threads woken by a
// condition variable. drape runs its stages on it through drape::TaskSystem (one ParallelFor per
// stage: call every chunk once, return when all are done); a real engine forwards these to its
// job scheduler instead. Nothing here allocates after construction.
#pragma once

#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <mutex>
#include <thread>
#include <vector>

#include "drape/runtime/task_system.h"

class EngineJobs final : public drape::TaskSystem {
 public:
  explicit EngineJobs(uint32_t threads) : threads_(threads < 1 ? 1 : threads) {
    for (uint32_t k = 1; k < threads_; ++k) workers_.emplace_back([this] { WorkerLoop(); });
  }
  ~EngineJobs() override {
    {
      std::lock_guard lock(mutex_);
      stop_ = true;
    }
    wake_.notify_all();
    for (std::thread& t : workers_) t.join();
  }

  void ParallelFor(uint32_t chunk_count, drape::TaskFunction run, void* context) override {
    {
      // A worker still inside the previous job would claim this one's chunks with its function.
      std::unique_lock lock(mutex_);
      idle_.wait(lock, [this] { return busy_ == 0; });
      job_ = {run, context, chunk_count};
      next_.store(0);
      finished_ = 0;
      ++generation_;
    }
    wake_.notify_all();
    RunChunks(job_);
    std::unique_lock lock(mutex_);
    done_.wait(lock, [&] { return finished_ == chunk_count; });
  }
  uint32_t WorkerCount() const override { return threads_; }

 private:
  struct Job {
    drape::TaskFunction run = nullptr;
    void* context = nullptr;
    uint32_t count = 0;
  };

  void RunChunks(const Job& job) {
    uint32_t ran = 0;
    for (uint32_t c = next_.fetch_add(1); c < job.count; c = next_.fetch_add(1)) {
      job.run(job.context, c);
      ++ran;
    }
    if (ran == 0) return;
    std::lock_guard lock(mutex_);
    finished_ += ran;
    if (finished_ == job.count) done_.notify_one();
  }

  void WorkerLoop() {
    uint64_t seen = 0;
    for (;;) {
      Job job;
      {
        std::unique_lock lock(mutex_);
        wake_.wait(lock, [&] { return stop_ || generation_ != seen; });
        if (stop_) return;
        seen = generation_;
        job = job_;
        ++busy_;
      }
      RunChunks(job);
      std::lock_guard lock(mutex_);
      if (--busy_ == 0) idle_.notify_one();
    }
  }

  const uint32_t threads_;
  std::vector<std::thread> workers_;
  std::mutex mutex_;
  std::condition_variable wake_, done_, idle_;
  Job job_;
  std::atomic<uint32_t> next_{0};
  uint32_t finished_ = 0, busy_ = 0;
  uint64_t generation_ = 0;
  bool stop_ = false;
};
