#pragma once
// Runs the runtime on a chosen number of workers, for the same-bits-at-any-worker-count checks,
// with or without OpenMP (-DDRAPE_OPENMP=OFF): 1 is the serial task system, 2 or more a
// std::thread pool of that size (one per size, kept for the test process).

#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "drape/runtime/task_system.h"

namespace drape::test {

inline void UseWorkers(int workers) {
  if (workers <= 1) {
    SetTaskSystem(&SerialTaskSystem());
    return;
  }
  static std::mutex mutex;
  static std::map<int, std::unique_ptr<ThreadPoolTaskSystem>> pools;
  const std::lock_guard lock(mutex);
  std::unique_ptr<ThreadPoolTaskSystem>& pool = pools[workers];
  if (pool == nullptr)
    pool = std::make_unique<ThreadPoolTaskSystem>(static_cast<uint32_t>(workers));
  SetTaskSystem(pool.get());
}

// Back to the runtime's default task system (OpenMP's team when built with it).
inline void UseDefaultWorkers() { SetTaskSystem(nullptr); }

// A job system that runs the chunks on the calling thread from the last to the first: results
// must not depend on the order either.
class ReverseOrderTaskSystem final : public TaskSystem {
 public:
  void ParallelFor(uint32_t chunk_count, TaskFunction run, void* context) override {
    for (uint32_t c = chunk_count; c-- > 0;) run(context, c);
  }
  uint32_t WorkerCount() const override { return 3; }
};

// The task systems a result must not depend on: serial (first), the pool at 2 and 4 workers,
// the reverse order, and OpenMP's team when built with it. Use() makes one the current one.
struct TaskSystemCase {
  enum Kind { kPool, kReverse, kOpenMp };
  std::string name;
  int workers = 1;  // kPool: 1 is the serial task system
  Kind kind = kPool;
  void Use() const {
    static ReverseOrderTaskSystem reverse;
    if (kind == kPool) return UseWorkers(workers);
    SetTaskSystem(kind == kReverse ? &reverse : OpenMpTaskSystem());
  }
};

inline std::vector<TaskSystemCase> AllTaskSystems() {
  std::vector<TaskSystemCase> cases = {{"serial", 1},
                                       {"pool of 2", 2},
                                       {"pool of 4", 4},
                                       {"reverse order", 1, TaskSystemCase::kReverse}};
  if (OpenMpTaskSystem() != nullptr) cases.push_back({"OpenMP", 1, TaskSystemCase::kOpenMp});
  return cases;
}

}  // namespace drape::test
