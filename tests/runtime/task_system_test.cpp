// The task interface: the std::thread pool runs every chunk exactly once under load, the default
// and the setter behave as documented, and an engine's own task system receives the runtime's
// work. (The same-bits-under-every-task-system checks are in each collider's and the solver's
// tests, through tests/support/workers.h.)
#include <gtest/gtest.h>

#include <atomic>
#include <cstring>
#include <vector>

#include "drape/runtime/cloth.h"
#include "drape/runtime/cloth_solver.h"
#include "drape/runtime/task_system.h"

#include "cloth_fixtures.h"
#include "workers.h"

namespace drape {
namespace {

struct ChunkCounts {
  std::vector<std::atomic<uint32_t>> hits;
  explicit ChunkCounts(size_t n) : hits(n) {}
};

void CountChunk(void* context, uint32_t chunk) {
  static_cast<ChunkCounts*>(context)->hits[chunk].fetch_add(1, std::memory_order_relaxed);
}

TEST(ThreadPoolTaskSystem, RunsEveryChunkExactlyOnce) {
  for (uint32_t workers : {1u, 2u, 4u, 7u}) {
    ThreadPoolTaskSystem pool(workers);
    EXPECT_EQ(pool.WorkerCount(), workers);
    // Many dispatches back to back: a worker late for one must not take chunks of the next.
    for (int round = 0; round < 300; ++round) {
      for (uint32_t chunks : {2u, 3u, 5u, 64u, 1000u}) {
        ChunkCounts counts(chunks);
        pool.ParallelFor(chunks, CountChunk, &counts);
        for (uint32_t c = 0; c < chunks; ++c)
          ASSERT_EQ(counts.hits[c].load(), 1u)
              << workers << " workers, " << chunks << " chunks, round " << round << ", chunk " << c;
      }
    }
  }
}

TEST(ThreadPoolTaskSystem, ZeroAndOneChunkRunOnTheCaller) {
  ThreadPoolTaskSystem pool(3);
  ChunkCounts counts(1);
  pool.ParallelFor(0, CountChunk, &counts);
  EXPECT_EQ(counts.hits[0].load(), 0u);
  pool.ParallelFor(1, CountChunk, &counts);
  EXPECT_EQ(counts.hits[0].load(), 1u);
  EXPECT_EQ(ThreadPoolTaskSystem(0).WorkerCount(), 1u);  // clamped
}

TEST(TaskSystem, DefaultIsOpenMpWhenBuiltWithItElseSerial) {
  SetTaskSystem(nullptr);
  TaskSystem* expected = OpenMpTaskSystem() != nullptr ? OpenMpTaskSystem() : &SerialTaskSystem();
  EXPECT_EQ(&GetTaskSystem(), expected);
  ThreadPoolTaskSystem pool(2);
  SetTaskSystem(&pool);
  EXPECT_EQ(&GetTaskSystem(), &pool);
  SetTaskSystem(nullptr);
  EXPECT_EQ(&GetTaskSystem(), expected);
  EXPECT_EQ(SerialTaskSystem().WorkerCount(), 1u);
}

// An engine's job system, here one that records what it is given and runs it serially.
class RecordingTaskSystem final : public TaskSystem {
 public:
  void ParallelFor(uint32_t chunk_count, TaskFunction run, void* context) override {
    ++calls;
    chunks += chunk_count;
    for (uint32_t c = 0; c < chunk_count; ++c) run(context, c);
  }
  uint32_t WorkerCount() const override { return 2; }
  uint64_t calls = 0, chunks = 0;
};

// A 10k-particle sheet's step goes through the engine's task system (the runtime runs nothing in
// parallel on its own), in chunks fixed by the cloth alone: the same chunks every step.
TEST(TaskSystem, ClothStepRunsThroughTheEnginesTaskSystem) {
  Cloth cloth;
  ASSERT_TRUE(BuildCloth(test::SheetDescription(99, 1.f, {0.f, 1.f, 0.f}), &cloth).ok());
  ClothSolver solver;
  ASSERT_TRUE(solver.Init(cloth, ClothSolverSettings{}).ok());
  ClothState state;
  state.Reset(cloth);
  RecordingTaskSystem engine;
  SetTaskSystem(&engine);
  ClothFrame frame;  // a free sheet falling: no joint needed
  frame.dt = 1.f / 60.f;
  ASSERT_TRUE(solver.Step(&state, ClothColliders{}, frame).ok());
  const uint64_t calls = engine.calls, chunks = engine.chunks;
  // Every spring pass (the iterations and the strain limit's) and at least the integration, the
  // constraints with the velocities, and the contact count.
  EXPECT_GE(calls, solver.settings().iterations + 1u + 3u);
  EXPECT_GT(chunks, calls * 2);
  ASSERT_TRUE(solver.Step(&state, ClothColliders{}, frame).ok());
  EXPECT_EQ(engine.calls, 2 * calls);
  EXPECT_EQ(engine.chunks, 2 * chunks);
  SetTaskSystem(nullptr);
}

}  // namespace
}  // namespace drape
