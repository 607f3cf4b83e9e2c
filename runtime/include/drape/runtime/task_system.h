#pragma once
// How the runtime runs in parallel: only through a TaskSystem, which an engine implements with its
// own job system. The runtime splits each parallel stage into chunks whose bounds depend on the
// data alone (particle, spring or texel counts), or that follow WorkerCount() only where any split
// gives the same bits (the cloth's spring passes), and every chunk writes its own slots: the
// results are bit-identical under any task system and worker count. Three implementations come with
// the runtime: serial (the calling thread), OpenMP's team (when built with DRAPE_OPENMP) and a
// small std::thread pool.
//
//   class EngineTasks final : public drape::TaskSystem {
//    public:
//     void ParallelFor(uint32_t chunk_count, drape::TaskFunction run, void* context) override {
//       // run(context, c) for every c in [0, chunk_count) on the engine's workers, then wait
//     }
//     uint32_t WorkerCount() const override { return engine_workers + 1; }
//   };
//   EngineTasks tasks;
//   drape::SetTaskSystem(&tasks);  // at start-up, before the first drape call that runs work
//
// The task system is process-wide: one engine, one job system. Set it while no drape call runs.

#include <atomic>
#include <cstdint>
#include <memory>

namespace drape {

// One chunk of a parallel stage. Chunks of one ParallelFor write disjoint data.
using TaskFunction = void (*)(void* context, uint32_t chunk);

class TaskSystem {
 public:
  virtual ~TaskSystem() = default;
  // Calls run(context, c) exactly once for every c in [0, chunk_count), from any threads in any
  // order, and returns when every call has returned. chunk_count >= 2 (a single chunk runs on the
  // caller). The chunks never call ParallelFor themselves. For an allocation-free
  // ClothSolver::Step, this must not allocate either.
  virtual void ParallelFor(uint32_t chunk_count, TaskFunction run, void* context) = 0;
  // Threads that run chunks at once, >= 1. A hint for how finely to split a stage (the body-map
  // renderer's row bands, the cloth's spring passes); it never changes a result.
  virtual uint32_t WorkerCount() const = 0;
};

// The task system every runtime call uses. Until set: OpenMP's team when the runtime was built
// with DRAPE_OPENMP, else the serial one. nullptr restores that default.
void SetTaskSystem(TaskSystem* tasks);
TaskSystem& GetTaskSystem();

// Runs every chunk in order on the calling thread.
TaskSystem& SerialTaskSystem();
// OpenMP's team (OMP_NUM_THREADS, omp_set_num_threads); nullptr when built without OpenMP.
TaskSystem* OpenMpTaskSystem();

// A fixed pool of std::threads: `workers` threads run chunks, the calling thread among them (so
// workers - 1 are started). Idle workers spin for a few microseconds, then sleep on an atomic
// wait. ParallelFor allocates nothing. One ParallelFor at a time (the runtime never nests them).
class ThreadPoolTaskSystem final : public TaskSystem {
 public:
  explicit ThreadPoolTaskSystem(uint32_t workers);  // workers >= 1, clamped to [1, 256]
  ~ThreadPoolTaskSystem() override;
  ThreadPoolTaskSystem(const ThreadPoolTaskSystem&) = delete;
  ThreadPoolTaskSystem& operator=(const ThreadPoolTaskSystem&) = delete;

  void ParallelFor(uint32_t chunk_count, TaskFunction run, void* context) override;
  uint32_t WorkerCount() const override;

 private:
  struct Pool;
  std::unique_ptr<Pool> pool_;
};

}  // namespace drape
