#include "import/child_process.h"

#include <fcntl.h>
#include <poll.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <new>
#include <vector>

#if defined(__SANITIZE_ADDRESS__)
#define DRAPE_ADDRESS_SANITIZER 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define DRAPE_ADDRESS_SANITIZER 1
#endif
#endif

namespace drape::bake::detail {
namespace {

// What the child reports through the pipe: one of these, the status code, the message.
enum class Outcome : uint8_t { kStatus = 1, kOutOfMemory = 2 };

std::string MiB(uint64_t bytes) { return std::to_string(bytes >> 20) + " MiB"; }

#ifndef DRAPE_ADDRESS_SANITIZER
// The child's address space so far, bytes (/proc/self/statm's first field, in pages).
uint64_t AddressSpaceInUse() {
  unsigned long pages = 0;
  if (FILE* statm = std::fopen("/proc/self/statm", "r")) {
    if (std::fscanf(statm, "%lu", &pages) != 1) pages = 0;
    std::fclose(statm);
  }
  return static_cast<uint64_t>(pages) * static_cast<uint64_t>(sysconf(_SC_PAGESIZE));
}
#endif

void WriteAll(int fd, const void* data, size_t size) {
  const char* p = static_cast<const char*>(data);
  while (size > 0) {
    const ssize_t n = write(fd, p, size);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) return;
    p += n;
    size -= static_cast<size_t>(n);
  }
}

// The child: limits, the step, its outcome down the pipe, and out without running the parent's
// exit handlers or flushing its buffers.
[[noreturn]] void RunChild(int fd, const ChildLimits& limits, const std::function<Status()>& step) {
  if (const int null = open("/dev/null", O_WRONLY); null >= 0) {
    dup2(null, STDOUT_FILENO);
    dup2(null, STDERR_FILENO);
    close(null);
  }
#ifndef DRAPE_ADDRESS_SANITIZER
  if (limits.memory_bytes > 0) {
    const rlim_t cap = static_cast<rlim_t>(AddressSpaceInUse() + limits.memory_bytes);
    const rlimit limit{cap, cap};
    setrlimit(RLIMIT_AS, &limit);
  }
#endif
  Outcome outcome = Outcome::kStatus;
  Status status;
  try {
    status = step();
    // assimp turns a failed allocation into its error text.
    if (limits.memory_bytes > 0 && status.message().find("bad_alloc") != std::string::npos)
      outcome = Outcome::kOutOfMemory;
  } catch (const std::bad_alloc&) {
    outcome = Outcome::kOutOfMemory;
  } catch (const std::exception& e) {
    status = Status(StatusCode::kCorrupt, e.what());
  } catch (...) {
    status = Status(StatusCode::kCorrupt, "an unknown exception");
  }
  const uint8_t header[2] = {static_cast<uint8_t>(outcome), static_cast<uint8_t>(status.code())};
  WriteAll(fd, header, sizeof(header));
  WriteAll(fd, status.message().data(), status.message().size());
  close(fd);
  _exit(0);
}

// Everything the child writes until it closes the pipe; false when `deadline` passes first.
bool ReadUntilClosed(int fd, std::chrono::steady_clock::time_point deadline, bool limited,
                     std::vector<char>* bytes) {
  char buffer[4096];
  for (;;) {
    int wait_ms = -1;
    if (limited) {
      const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(
          deadline - std::chrono::steady_clock::now());
      if (left.count() <= 0) return false;
      wait_ms = static_cast<int>(std::min<long long>(left.count(), 1 << 30));
    }
    pollfd p{fd, POLLIN, 0};
    const int ready = poll(&p, 1, wait_ms);
    if (ready < 0 && errno == EINTR) continue;
    if (ready == 0) return false;
    const ssize_t n = read(fd, buffer, sizeof(buffer));
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) return true;
    bytes->insert(bytes->end(), buffer, buffer + n);
  }
}

int WaitFor(pid_t pid) {
  int status = 0;
  while (waitpid(pid, &status, 0) < 0 && errno == EINTR) {
  }
  return status;
}

}  // namespace

Status RunInChildProcess(const std::string& subject, const ChildLimits& limits,
                         const std::function<Status()>& step) {
  int fds[2];
  if (pipe(fds) != 0)
    return Status(StatusCode::kIoError, subject + ": cannot create a pipe for the import");
  std::fflush(stdout);
  std::fflush(stderr);
  const pid_t pid = fork();
  if (pid < 0) {
    close(fds[0]);
    close(fds[1]);
    return Status(StatusCode::kIoError, subject + ": cannot start the import process");
  }
  if (pid == 0) {
    close(fds[0]);
    RunChild(fds[1], limits, step);
  }
  close(fds[1]);
  const auto deadline = std::chrono::steady_clock::now() +
                        std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                            std::chrono::duration<double>(limits.time_s));
  std::vector<char> report;
  const bool finished = ReadUntilClosed(fds[0], deadline, limits.time_s > 0.0, &report);
  close(fds[0]);
  if (!finished) {
    kill(pid, SIGKILL);
    WaitFor(pid);
    char seconds[32];
    std::snprintf(seconds, sizeof(seconds), "%g", limits.time_s);
    return Status(StatusCode::kCorrupt, subject + ": reading it took longer than the import's " +
                                            seconds + " s time limit (import.time_limit_s)");
  }
  const int wait_status = WaitFor(pid);
  if (WIFSIGNALED(wait_status) || report.size() < 2) {
    const int signal = WIFSIGNALED(wait_status) ? WTERMSIG(wait_status) : 0;
    return Status(StatusCode::kCorrupt,
                  subject + ": the model reader crashed on this file (" +
                      (signal != 0 ? std::string("signal ") + std::to_string(signal) + ", " +
                                         strsignal(signal)
                                   : std::string("no report")) +
                      "): it is corrupt or uses what assimp cannot read");
  }
  if (static_cast<Outcome>(report[0]) == Outcome::kOutOfMemory) {
    return Status(StatusCode::kCorrupt, subject + ": reading it needs more than the import's " +
                                            MiB(limits.memory_bytes) +
                                            " memory limit (import.memory_limit_mb)");
  }
  const auto code = static_cast<StatusCode>(static_cast<uint8_t>(report[1]));
  if (code == StatusCode::kOk) return Status::Ok();
  return Status(code, std::string(report.begin() + 2, report.end()));
}

}  // namespace drape::bake::detail
