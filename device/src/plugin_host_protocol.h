#pragma once
// The wire format between PluginDevice (isolated) and torsion_device_host: one page of shared
// memory (a memfd the host inherits as file descriptor kHostChannelFd) holding a single
// request/response slot.
//
//   Torsion writes the request fields only while the host is idle (response == request), then
//   bumps `request` (release) and wakes the host's futex; the host reads the fields, calls the
//   plug-in, writes the response fields, stores `response` = `request` (release) and wakes
//   Torsion's futex. So each side touches the fields only while the other waits: no lock.
//   Request 1 is implicit: the host's answer to it is the outcome of opening the library
//   (`status` 0 and `info`, or `status` != 0 and `error`).
//
// Torsion checks every value it gets back exactly as if the plug-in had returned it in process.

#include <linux/futex.h>
#include <sys/syscall.h>
#include <unistd.h>

#include <atomic>
#include <cstdint>
#include <ctime>

#include "torsion/device/plugin_abi.h"

namespace torsion::device::host {

constexpr int kHostChannelFd = 3;  ///< where the host finds the channel's memfd

enum class Op : std::uint32_t {
  kRead = 1,   ///< write(wrench) if has_wrench, then read(time)
  kClose = 2,  ///< write(wrench) if has_wrench, then close(); the host then exits 0
};

struct Channel {
  // Futex words (32-bit, lock-free, so usable across processes).
  std::atomic<std::uint32_t> request{0};
  std::atomic<std::uint32_t> response{0};
  // Request, written by Torsion.
  Op op = Op::kRead;
  std::uint32_t has_wrench = 0;
  double time = 0;
  double wrench[6] = {};
  // Response, written by the host.
  std::int32_t status = 0;        ///< read()'s return, or the open's outcome (0: opened)
  std::int32_t write_status = 0;  ///< write()'s return when the request carried a wrench
  torsion_device_state state{};
  torsion_device_info info{};
  char error[1024] = {};  ///< NUL-terminated: why the library could not be opened
  // Set by Torsion before the host starts (PluginDeviceSettings).
  double watchdog_timeout = 0.1;    ///< s without a wrench before the host fades; 0: never
  double watchdog_fade_time = 0.2;  ///< s from the limit to zero
};

static_assert(std::atomic<std::uint32_t>::is_always_lock_free);
static_assert(sizeof(std::atomic<std::uint32_t>) == sizeof(std::uint32_t));

/// Sleeps while `*word == expected`, at most `seconds` (FUTEX_WAIT on shared memory: no
/// FUTEX_PRIVATE_FLAG). Returns early on a wake-up, a signal or a changed word.
inline void futexWait(std::atomic<std::uint32_t>& word, std::uint32_t expected, double seconds) {
  if (!(seconds > 0)) return;
  timespec timeout{};
  timeout.tv_sec = static_cast<time_t>(seconds);
  timeout.tv_nsec = static_cast<long>((seconds - static_cast<double>(timeout.tv_sec)) * 1e9);
  syscall(SYS_futex, reinterpret_cast<std::uint32_t*>(&word), FUTEX_WAIT, expected, &timeout,
          nullptr, 0);
}

inline void futexWake(std::atomic<std::uint32_t>& word) {
  syscall(SYS_futex, reinterpret_cast<std::uint32_t*>(&word), FUTEX_WAKE, 1, nullptr, nullptr, 0);
}

}  // namespace torsion::device::host
