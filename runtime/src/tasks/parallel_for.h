#pragma once
// Private to the runtime: how its stages hand work to the task system (drape/runtime/
// task_system.h). Chunk bounds depend on the counts alone, so results never depend on the
// threads.

#include <algorithm>
#include <atomic>
#include <cstdint>

#include "drape/runtime/task_system.h"

namespace drape::detail {

// Calls fn(begin, end) for the ranges [k grain, min((k + 1) grain, count)) that cover
// [0, count), through the task system when there are two or more (grain >= 1). Allocates nothing.
template <class Fn>
void ParallelRanges(int64_t count, int64_t grain, const Fn& fn) {
  if (count <= 0) return;
  grain = std::max<int64_t>(grain, 1);
  const int64_t chunks = (count + grain - 1) / grain;
  if (chunks == 1) {
    fn(int64_t{0}, count);
    return;
  }
  struct Job {
    const Fn* fn;
    int64_t count, grain;
  } job{&fn, count, grain};
  const TaskFunction run = [](void* context, uint32_t chunk) {
    const Job& j = *static_cast<const Job*>(context);
    const int64_t begin = static_cast<int64_t>(chunk) * j.grain;
    (*j.fn)(begin, std::min(j.count, begin + j.grain));
  };
  GetTaskSystem().ParallelFor(static_cast<uint32_t>(chunks), run, &job);
}

// Calls fn(i) for every i in [0, count), `grain` indices per chunk.
template <class Fn>
void ParallelFor(int64_t count, int64_t grain, const Fn& fn) {
  ParallelRanges(count, grain, [&fn](int64_t begin, int64_t end) {
    for (int64_t i = begin; i < end; ++i) fn(i);
  });
}

// Particles per chunk of a per-particle stage: below two chunks' worth (2048 particles) a stage
// stays on the calling thread, where waking workers would cost more than it saves.
constexpr int64_t kParticleGrain = 1024;

// A sum over chunks: integer addition, so the same in any order.
class ChunkSum {
 public:
  void Add(uint32_t value) { total_.fetch_add(value, std::memory_order_relaxed); }
  uint32_t total() const { return total_.load(std::memory_order_relaxed); }

 private:
  std::atomic<uint32_t> total_{0};
};

}  // namespace drape::detail
