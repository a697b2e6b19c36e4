#include "isolated_call.h"

#include <fcntl.h>
#include <poll.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <csignal>
#include <cstring>
#include <fstream>
#include <new>

#include "torsion/format_number.h"

// The sanitizers reserve terabytes of address space for their shadow memory: no RLIMIT_AS there.
#if defined(__SANITIZE_ADDRESS__) || defined(__SANITIZE_THREAD__)
#define TORSION_ISOLATED_SANITIZED 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer) || __has_feature(thread_sanitizer) || \
    __has_feature(memory_sanitizer)
#define TORSION_ISOLATED_SANITIZED 1
#endif
#endif

#ifdef TORSION_ISOLATED_SANITIZED
#include <sanitizer/common_interface_defs.h>
#endif

namespace torsion::scene {

namespace {

// The first byte of the child's answer: what follows is the work's bytes, its error's message,
// or nothing (it ran out of memory).
constexpr char kAnswer = 'A';
constexpr char kError = 'E';
constexpr char kOutOfMemory = 'M';

#ifndef TORSION_ISOLATED_SANITIZED
// The address space this process has mapped (bytes): the child inherits it.
std::size_t mappedBytes() {
  std::ifstream statm("/proc/self/statm");
  std::size_t pages = 0;
  statm >> pages;
  return pages * static_cast<std::size_t>(sysconf(_SC_PAGESIZE));
}
#endif

void writeAll(int fd, const char* data, std::size_t size) {
  while (size > 0) {
    const ssize_t n = write(fd, data, size);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) return;  // the parent has gone or refused: nothing else to do
    data += n;
    size -= static_cast<std::size_t>(n);
  }
}

[[noreturn]] void childMain(int out, const std::function<Result<std::string>()>& work,
                            const IsolationLimits& limits) {
  // What the work prints is not the parent's output.
  const int null = open("/dev/null", O_WRONLY | O_CLOEXEC);
  if (null >= 0) {
    dup2(null, STDOUT_FILENO);
    dup2(null, STDERR_FILENO);
  }
  // The parent's handlers are not the child's. Its stop handlers (Ctrl-C, SIGTERM) set a flag the
  // child never reads: a stop kills the child at once instead, and the parent reports it. Its crash
  // handlers (Python's faulthandler, a crash reporter, libFuzzer's) would report the child's crash
  // as the parent's: the child dies by the signal, and the parent says so.
  for (int sig :
       {SIGINT, SIGTERM, SIGHUP, SIGPIPE, SIGSEGV, SIGBUS, SIGABRT, SIGFPE, SIGILL, SIGTRAP})
    std::signal(sig, SIG_DFL);
#ifdef TORSION_ISOLATED_SANITIZED
  // A sanitizer's report ends the child through its death callbacks (libFuzzer's writes a crash
  // file for the parent's input): none in the child, the report alone (to /dev/null) and exit 1.
  __sanitizer_set_death_callback(nullptr);
#endif
  const rlimit cpu{static_cast<rlim_t>(limits.cpu_seconds),
                   static_cast<rlim_t>(limits.cpu_seconds)};
  setrlimit(RLIMIT_CPU, &cpu);
#ifndef TORSION_ISOLATED_SANITIZED
  const rlim_t space = static_cast<rlim_t>(mappedBytes() + limits.memory_bytes);
  const rlimit memory{space, space};
  setrlimit(RLIMIT_AS, &memory);
#endif
  std::string answer;
  try {
    Result<std::string> result = work();
    answer = result ? kAnswer + result.value() : kError + result.error().message;
  } catch (const std::bad_alloc&) {
    answer = std::string(1, kOutOfMemory);
  } catch (const std::exception& e) {
    answer = kError + std::string(e.what());
  } catch (...) {
    answer = kError + std::string("an exception that is not a std::exception");
  }
  writeAll(out, answer.data(), answer.size());
  _exit(0);
}

std::string describeSignal(int sig) {
  const char* name = strsignal(sig);
  return "signal " + std::to_string(sig) + (name != nullptr ? std::string(", ") + name : "");
}

}  // namespace

Result<std::string> runIsolated(const std::function<Result<std::string>()>& work,
                                const std::string& what, const IsolationLimits& limits) {
  int fds[2];
  if (pipe2(fds, O_CLOEXEC) != 0)
    return Error{what + " could not start: no pipe (" + std::strerror(errno) + ")"};
  const pid_t child = fork();
  if (child < 0) {
    const int error = errno;
    close(fds[0]);
    close(fds[1]);
    return Error{what + " could not start: fork failed (" + std::strerror(error) + ")"};
  }
  if (child == 0) {
    close(fds[0]);
    childMain(fds[1], work, limits);
  }
  close(fds[1]);

  using Clock = std::chrono::steady_clock;
  const Clock::time_point deadline =
      Clock::now() + std::chrono::duration_cast<Clock::duration>(
                         std::chrono::duration<double>(limits.wall_seconds));
  std::string answer;
  std::string fault;  // set when this side stopped the child
  char buffer[1 << 16];
  for (;;) {
    const auto left =
        std::chrono::duration_cast<std::chrono::milliseconds>(deadline - Clock::now()).count();
    if (left <= 0) {
      fault = "did not finish within " + formatNumber(limits.wall_seconds) + " s";
      break;
    }
    pollfd p{fds[0], POLLIN, 0};
    const int ready = poll(&p, 1, static_cast<int>(std::min<long long>(left, 1000)));
    if (ready < 0 && errno != EINTR) {
      fault = std::string("could not be read (") + std::strerror(errno) + ")";
      break;
    }
    if (ready <= 0) continue;
    const ssize_t n = read(fds[0], buffer, sizeof buffer);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) break;  // end of the answer (or a read error, judged by the exit status below)
    answer.append(buffer, static_cast<std::size_t>(n));
    if (answer.size() > limits.output_bytes + 1) {
      fault = "answered with more than " + std::to_string(limits.output_bytes >> 20) + " MiB";
      break;
    }
  }
  close(fds[0]);
  if (!fault.empty()) kill(child, SIGKILL);
  int status = 0;
  while (waitpid(child, &status, 0) < 0 && errno == EINTR) {
  }
  if (!fault.empty()) return Error{what + " " + fault};
  if (WIFSIGNALED(status)) {
    const int sig = WTERMSIG(status);
    if (sig == SIGXCPU || sig == SIGKILL)
      return Error{what + " used more than " + std::to_string(limits.cpu_seconds) +
                   " s of processor time (" + describeSignal(sig) + ")"};
    return Error{what + " crashed (" + describeSignal(sig) + ")"};
  }
  if (!WIFEXITED(status) || WEXITSTATUS(status) != 0 || answer.empty()) {
    // A sanitizer's report ends the child with status 1 before it answers.
    return Error{what + " crashed (exit status " +
                 std::to_string(WIFEXITED(status) ? WEXITSTATUS(status) : -1) + ", no answer)"};
  }
  switch (answer[0]) {
    case kAnswer:
      return answer.substr(1);
    case kError:
      return Error{answer.substr(1)};
    case kOutOfMemory:
      return Error{what + " needed more than " + std::to_string(limits.memory_bytes >> 20) +
                   " MiB of memory"};
    default:
      return Error{what + " answered in a form it never writes"};
  }
}

}  // namespace torsion::scene
