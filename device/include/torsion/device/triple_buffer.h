#pragma once
// Lock-free exchange of one plain struct between exactly one writer thread and one reader thread:
// the writer never waits, the reader always gets the newest complete value. Three slots: the
// writer fills its back slot and swaps it with the middle one (atomically, with a "fresh" bit);
// the reader swaps the middle slot with its front slot when the bit is set. No slot is ever
// touched by both threads at once, so T needs no atomics of its own (it must be trivially
// copyable: the structs in device_types.h are).

#include <array>
#include <atomic>
#include <cstdint>
#include <type_traits>

namespace torsion::device {

template <class T>
class TripleBuffer {
  static_assert(std::is_trivially_copyable_v<T>, "TripleBuffer carries plain structs only");

 public:
  TripleBuffer() = default;
  explicit TripleBuffer(const T& initial) { slots_.fill(initial); }

  /// Writer thread only.
  void write(const T& value) {
    slots_[back_] = value;
    const std::uint8_t published = static_cast<std::uint8_t>(back_ | kFresh);
    const std::uint8_t previous = middle_.exchange(published, std::memory_order_acq_rel);
    back_ = previous & kIndex;
  }

  /// Reader thread only: the newest value written (or the last one read, if nothing new).
  /// Returns true when the value is new since the previous read().
  bool read(T& out) {
    bool fresh = false;
    if (middle_.load(std::memory_order_relaxed) & kFresh) {
      const std::uint8_t previous = middle_.exchange(front_, std::memory_order_acq_rel);
      front_ = previous & kIndex;
      fresh = true;
    }
    out = slots_[front_];
    return fresh;
  }

 private:
  static constexpr std::uint8_t kIndex = 0x3;
  static constexpr std::uint8_t kFresh = 0x4;
  std::array<T, 3> slots_{};
  std::uint8_t back_ = 0;                // writer's
  std::atomic<std::uint8_t> middle_{1};  // shared
  std::uint8_t front_ = 2;               // reader's
};

}  // namespace torsion::device
