#pragma once
// The newest value from one writer thread, readable by any thread without locks: a seqlock over two slots.
// The writer fills the slot readers are not pointed at, then points them at it, so a reader never waits for a
// writer that was preempted half-way (the board's real-time loop may preempt the poll thread on its CPU). A
// read is retried only when the writer completed at least one more value during it: lock-free, and in
// practice wait-free since reads take nanoseconds and writes come milliseconds apart. Fields are stored as
// relaxed atomic words with the fences of Boehm's seqlock ("Can seqlocks get along with programming language
// memory models?", 2012), so there is no data race, not even a benign one.
#include <array>
#include <atomic>
#include <cstdint>
#include <cstring>
#include <optional>
#include <type_traits>

namespace lever::board {

template <typename T>
requires std::is_trivially_copyable_v<T> && std::is_default_constructible_v<T>
class LatestValue {
 public:
  // Only ever called from one thread.
  void publish(const T& value) noexcept {
    std::array<std::uint64_t, kWords> buffer{};
    std::memcpy(buffer.data(), &value, sizeof(T));
    const std::uint64_t next = published_.load(std::memory_order_relaxed) + 1;
    Slot& slot = slots_[next & 1];
    slot.version.store(2 * next - 1, std::memory_order_relaxed);
    std::atomic_thread_fence(std::memory_order_release);
    for (std::size_t i = 0; i < kWords; ++i) slot.words[i].store(buffer[i], std::memory_order_relaxed);
    slot.version.store(2 * next, std::memory_order_release);
    published_.store(next, std::memory_order_release);
  }

  // Never blocks, never allocates; empty before the first publish().
  std::optional<T> load() const noexcept {
    for (;;) {
      const std::uint64_t newest = published_.load(std::memory_order_acquire);
      if (newest == 0) return std::nullopt;
      const Slot& slot = slots_[newest & 1];
      // Exactly publication `newest`, not a later one the writer put there before announcing it: readers
      // then never see values go back, as they could if a lapped slot were taken while published_ lagged.
      const std::uint64_t before = slot.version.load(std::memory_order_acquire);
      if (before != 2 * newest) continue;
      std::array<std::uint64_t, kWords> buffer{};
      for (std::size_t i = 0; i < kWords; ++i) buffer[i] = slot.words[i].load(std::memory_order_relaxed);
      std::atomic_thread_fence(std::memory_order_acquire);
      if (slot.version.load(std::memory_order_relaxed) != before) continue;
      T value{};
      std::memcpy(static_cast<void*>(&value), buffer.data(), sizeof(T));  // T is trivially copyable
      return value;
    }
  }

 private:
  static constexpr std::size_t kWords = (sizeof(T) + sizeof(std::uint64_t) - 1) / sizeof(std::uint64_t);
  static_assert(std::atomic<std::uint64_t>::is_always_lock_free, "the handoff must not fall back to a lock");

  // One cache line each, so the writer filling one slot does not slow readers of the other.
  struct alignas(64) Slot {
    std::atomic<std::uint64_t> version{0};  // 2n - 1 while publication n is written into it, 2n once done
    std::array<std::atomic<std::uint64_t>, kWords> words{};
  };
  std::array<Slot, 2> slots_{};
  std::atomic<std::uint64_t> published_{0};  // how many values were published; the newest is in slot [n & 1]
};

}  // namespace lever::board
