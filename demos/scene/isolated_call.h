#pragma once
// Runs code that must not be trusted with this process (a third-party parser reading untrusted
// bytes: Bullet's .bullet reader is not memory-safe on malformed files) in a child process of its
// own, bounded in time and memory, and takes back only the bytes it returns. Whatever the code
// does (crash, hang, allocate without end, scribble over memory, print), this process sees a
// result or an error saying what went wrong.
//
// fork() without exec: the child is a copy of this process, so the code runs with the libraries
// already loaded and needs no program of its own to be found and installed (a Python wheel has
// none). The child only computes and writes to a pipe; it takes no lock another thread could hold
// except the allocator's, which glibc resets in the child of a fork. It never returns: it ends
// with _exit, so no atexit handler, stdio flush or destructor of the parent's objects runs twice.

#include <cstddef>
#include <functional>
#include <string>

#include "torsion/result.h"

namespace torsion::scene {

struct IsolationLimits {
  double wall_seconds = 20;  ///< the child is killed past this (a hang)
  int cpu_seconds = 20;      ///< RLIMIT_CPU (a busy loop, if the clock is unfair)
  /// Address space the child may add to what it inherited (RLIMIT_AS; not under ASan, which
  /// reserves terabytes of shadow).
  std::size_t memory_bytes = std::size_t{2} << 30;
  std::size_t output_bytes = std::size_t{256} << 20;  ///< a longer answer is refused
};

/// Runs `work` in a child process and returns what it returned: its bytes, or its Error's
/// message. `what` names the work in the errors of the isolation itself ("Bullet's .bullet
/// reader"): a crash (with its signal), a hang past the time limit, memory past the limit, an
/// answer past the size limit, or the child not starting.
Result<std::string> runIsolated(const std::function<Result<std::string>()>& work,
                                const std::string& what, const IsolationLimits& limits = {});

}  // namespace torsion::scene
