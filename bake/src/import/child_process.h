#pragma once
// Running a risky step (assimp on a file nobody has vetted) in a child process first, with a
// memory and a time limit, so that a loader that crashes, aborts on an assertion (Debian's
// libassimp is built with them on), loops or allocates from a hostile header costs a clear error
// instead of the caller's process (header importer.h).

#include <cstdint>
#include <functional>
#include <string>

#include "drape/formats/status.h"

namespace drape::bake::detail {

struct ChildLimits {
  uint64_t memory_bytes = 0;  // address space the child may add to what the parent uses; 0: none
  double time_s = 0.0;        // wall-clock seconds before the child is killed; 0: none
};

// Runs `step` in a forked child and returns its Status, or an error that names `subject` and what
// happened: killed by a signal, out of its memory limit, past its time limit. The child writes
// nothing to the parent's stdout or stderr. `step` must not need threads the parent started.
// The memory limit is not applied under AddressSanitizer (its shadow memory needs the address
// space).
Status RunInChildProcess(const std::string& subject, const ChildLimits& limits,
                         const std::function<Status()>& step);

}  // namespace drape::bake::detail
