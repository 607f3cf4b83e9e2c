#include "drape/runtime/task_system.h"

#include <algorithm>
#include <chrono>
#include <thread>
#include <vector>

#if defined(_OPENMP)
#include <omp.h>
#endif

namespace drape {
namespace {

class SerialTasks final : public TaskSystem {
 public:
  void ParallelFor(uint32_t chunk_count, TaskFunction run, void* context) override {
    for (uint32_t c = 0; c < chunk_count; ++c) run(context, c);
  }
  uint32_t WorkerCount() const override { return 1; }
};

#if defined(_OPENMP)
class OpenMpTasks final : public TaskSystem {
 public:
  void ParallelFor(uint32_t chunk_count, TaskFunction run, void* context) override {
    const int64_t count = chunk_count;
    // Static: each thread keeps the same particles stage after stage (see the pool below).
#pragma omp parallel for schedule(static)
    for (int64_t c = 0; c < count; ++c) run(context, static_cast<uint32_t>(c));
  }
  uint32_t WorkerCount() const override {
    return static_cast<uint32_t>(std::max(1, omp_get_max_threads()));
  }
};
#endif

TaskSystem& DefaultTaskSystem() {
#if defined(_OPENMP)
  static OpenMpTasks tasks;
  return tasks;
#else
  return SerialTaskSystem();
#endif
}

std::atomic<TaskSystem*> g_task_system{nullptr};

// A busy-wait hint to the CPU (x86 PAUSE): lets the sibling hyperthread run and saves power.
inline void CpuRelax() {
#if defined(__x86_64__) || defined(__i386__)
  __builtin_ia32_pause();
#endif
}

// Idle workers poll for this long before sleeping: a cloth step issues its stages microseconds
// apart, and a futex wake-up costs tens of microseconds (measured: a 1600-particle skirt's step
// 1.53 ms on one worker, 1.78 ms on two when workers slept after 45 us of polling, 1.54 ms after
// 450 us). Timed, not counted: a PAUSE takes 10 to 140 cycles depending on the CPU.
constexpr std::chrono::microseconds kSpinTime{200};

// Spins, then sleeps, until `value` differs from `old`; returns the new value.
uint32_t WaitWhileEqual(const std::atomic<uint32_t>& value, uint32_t old) {
  const auto spin_end = std::chrono::steady_clock::now() + kSpinTime;
  for (;;) {
    for (int k = 0; k < 64; ++k) {
      const uint32_t now = value.load(std::memory_order_acquire);
      if (now != old) return now;
      CpuRelax();
    }
    if (std::chrono::steady_clock::now() > spin_end) break;
  }
  for (;;) {
    value.wait(old, std::memory_order_acquire);
    const uint32_t now = value.load(std::memory_order_acquire);
    if (now != old) return now;
  }
}

// Spins, then sleeps, until `value` is 0 (it only decreases while waited on); returns it.
uint32_t WaitWhileNotZero(const std::atomic<uint32_t>& value, uint32_t seen) {
  while (seen != 0) seen = WaitWhileEqual(value, seen);
  return seen;
}

}  // namespace

void SetTaskSystem(TaskSystem* tasks) { g_task_system.store(tasks, std::memory_order_release); }

TaskSystem& GetTaskSystem() {
  TaskSystem* tasks = g_task_system.load(std::memory_order_acquire);
  return tasks != nullptr ? *tasks : DefaultTaskSystem();
}

TaskSystem& SerialTaskSystem() {
  static SerialTasks tasks;
  return tasks;
}

TaskSystem* OpenMpTaskSystem() {
#if defined(_OPENMP)
  return &DefaultTaskSystem();
#else
  return nullptr;
#endif
}

// ---- The std::thread pool ----------------------------------------------------------------------
// Worker w (the caller is 0) owns the contiguous share [w n / W, (w + 1) n / W) of the chunks and
// claims them in order from its cursor; when its share is done it takes what is left of the
// others' (balance when chunks differ in cost). Contiguous shares keep each worker on the same
// particles stage after stage: handing chunks out round-robin made the spring passes of a
// 10k-particle cloth 1.2x faster on two workers instead of 1.85x (cache lines travelling between
// the cores).
//
// The job (function, context, shares) is published like a seqlock: `generation` is odd while the
// caller writes it and even once published. A worker announces itself in `active`, then checks
// that the generation is still the one it woke for, and only then reads the job; the caller
// makes the generation odd and waits for `active` to drain before writing. So the caller returns
// as soon as every chunk is done (`done`), without waiting for workers that are still asleep: a
// small job on a pool whose workers sleep costs no wake-up latency.
struct ThreadPoolTaskSystem::Pool {
  struct alignas(64) Cursor {  // one cache line per worker
    std::atomic<uint32_t> next{0};
    uint32_t end = 0;
  };
  uint32_t workers = 1;
  std::vector<std::thread> threads;
  std::unique_ptr<Cursor[]> cursors;
  alignas(64) std::atomic<uint32_t> generation{0};
  alignas(64) std::atomic<uint32_t> active{0};
  alignas(64) std::atomic<uint32_t> done{0};
  // The job, on its own line: the workers only read it while `done` takes their counts.
  alignas(64) std::atomic<bool> stop{false};
  TaskFunction run = nullptr;
  void* context = nullptr;
  uint32_t count = 0;

  // The chunks a worker ran are added to `done` once, when it runs out of chunks: a shared
  // counter bumped per chunk moved its cache line between the cores for every chunk (measured: an
  // empty ParallelFor of 16 chunks on 2 workers 1.65 us that way).
  void RunChunks(uint32_t worker) {
    uint32_t ran = 0;
    for (uint32_t k = 0; k < workers; ++k) {
      Cursor& cursor = cursors[(worker + k) % workers];
      for (;;) {
        const uint32_t c = cursor.next.fetch_add(1, std::memory_order_relaxed);
        if (c >= cursor.end) break;
        run(context, c);
        ++ran;
      }
    }
    if (ran != 0 && done.fetch_add(ran, std::memory_order_acq_rel) + ran == count)
      done.notify_one();
  }

  void WorkerLoop(uint32_t worker) {
    uint32_t seen = 0;
    for (;;) {
      const uint32_t g = WaitWhileEqual(generation, seen);
      seen = g;
      if (stop.load(std::memory_order_acquire)) return;
      if (g % 2 != 0) continue;  // being written: wait for it to be published
      active.fetch_add(1, std::memory_order_seq_cst);
      if (generation.load(std::memory_order_seq_cst) == g) RunChunks(worker);
      active.fetch_sub(1, std::memory_order_seq_cst);
      active.notify_one();
    }
  }
};

ThreadPoolTaskSystem::ThreadPoolTaskSystem(uint32_t workers) : pool_(std::make_unique<Pool>()) {
  pool_->workers = std::clamp(workers, 1u, 256u);
  pool_->cursors = std::make_unique<Pool::Cursor[]>(pool_->workers);
  pool_->threads.reserve(pool_->workers - 1);
  for (uint32_t k = 1; k < pool_->workers; ++k)
    pool_->threads.emplace_back([pool = pool_.get(), k] { pool->WorkerLoop(k); });
}

ThreadPoolTaskSystem::~ThreadPoolTaskSystem() {
  pool_->stop.store(true, std::memory_order_release);
  pool_->generation.fetch_add(2, std::memory_order_acq_rel);
  pool_->generation.notify_all();
  for (std::thread& t : pool_->threads) t.join();
}

void ThreadPoolTaskSystem::ParallelFor(uint32_t chunk_count, TaskFunction run, void* context) {
  Pool& p = *pool_;
  if (p.workers == 1 || chunk_count < 2) {
    for (uint32_t c = 0; c < chunk_count; ++c) run(context, c);
    return;
  }
  // Close the previous job: no worker may read it from here on.
  p.generation.fetch_add(1, std::memory_order_seq_cst);  // odd: being written
  for (uint32_t a = p.active.load(std::memory_order_seq_cst); a != 0;)
    a = WaitWhileNotZero(p.active, a);
  p.run = run;
  p.context = context;
  p.count = chunk_count;
  p.done.store(0, std::memory_order_relaxed);
  for (uint32_t w = 0; w < p.workers; ++w) {
    p.cursors[w].next.store(static_cast<uint32_t>(uint64_t{w} * chunk_count / p.workers),
                            std::memory_order_relaxed);
    p.cursors[w].end = static_cast<uint32_t>(uint64_t{w + 1} * chunk_count / p.workers);
  }
  p.generation.fetch_add(1, std::memory_order_seq_cst);  // even: published
  p.generation.notify_all();
  p.RunChunks(0);
  for (uint32_t d = p.done.load(std::memory_order_acquire); d != chunk_count;)
    d = WaitWhileEqual(p.done, d);
}

uint32_t ThreadPoolTaskSystem::WorkerCount() const { return pool_->workers; }

}  // namespace drape
