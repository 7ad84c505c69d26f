#pragma once
// A sliding replay window over 64-bit sequence numbers (the IPsec/WireGuard scheme, RFC 6479): accepts each
// number once, as long as it is no more than Width - 1 behind the newest accepted, and says whether an accepted
// number arrived out of order or after a gap. Heap-free, constant size, no exceptions.
//
// Feed it only authenticated sequence numbers (after decode() succeeded): an unauthenticated number must not
// move the window. docs/datagram-format.md, "Sequence numbers and replay", explains the choices.
#include <array>
#include <cstddef>
#include <cstdint>

namespace lever::bridge {

enum class ReplayVerdict : std::uint8_t {
  accepted = 0,
  duplicate = 1,  // seen before, inside the window
  too_old = 2,    // Width or more behind the newest: cannot tell, so refused
};

struct ReplayResult {
  ReplayVerdict verdict = ReplayVerdict::accepted;
  // Accepted and older than the newest: how far behind it (1 = the one just before the newest). 0 otherwise.
  std::uint64_t reordered_by = 0;
  // Accepted and newer than the newest: how many numbers were skipped (0 = the next one). 0 otherwise and for
  // the very first number. Some of them may still arrive, reordered.
  std::uint64_t gap = 0;

  bool accepted() const noexcept { return verdict == ReplayVerdict::accepted; }
  bool reordered() const noexcept { return reordered_by != 0; }
};

// Width: how many numbers, the newest included, the window remembers; a multiple of 64.
template <std::size_t Width = 1024>
class ReplayWindow {
  static_assert(Width >= 64 && Width % 64 == 0, "the window is made of 64-bit words");

 public:
  static constexpr std::size_t kWidth = Width;

  // Checks `sequence` and, if accepted, records it.
  ReplayResult accept(std::uint64_t sequence) noexcept {
    if (!started_) {
      started_ = true;
      newest_ = sequence;
      words_.fill(0);
      set(sequence);
      return {};
    }
    if (sequence > newest_) {
      advance_to(sequence);
      ReplayResult result;
      result.gap = sequence - newest_ - 1;
      newest_ = sequence;
      set(sequence);
      return result;
    }
    const std::uint64_t behind = newest_ - sequence;
    if (behind >= Width) return {ReplayVerdict::too_old, 0, 0};
    if (test(sequence)) return {ReplayVerdict::duplicate, 0, 0};
    set(sequence);
    return {ReplayVerdict::accepted, behind, 0};
  }

  // Whether accept(sequence) would accept, without recording it.
  bool would_accept(std::uint64_t sequence) const noexcept {
    if (!started_ || sequence > newest_) return true;
    return newest_ - sequence < Width && !test(sequence);
  }

  // Forgets everything: the next number is accepted as the first.
  void reset() noexcept {
    started_ = false;
    newest_ = 0;
    words_.fill(0);
  }

  bool started() const noexcept { return started_; }
  std::uint64_t newest() const noexcept { return newest_; }

 private:
  // One word more than Width needs: advancing clears whole words, which costs up to 63 numbers of history.
  static constexpr std::size_t kWords = Width / 64 + 1;

  static std::size_t word_of(std::uint64_t sequence) noexcept {
    return static_cast<std::size_t>((sequence >> 6) % kWords);
  }
  static std::uint64_t bit_of(std::uint64_t sequence) noexcept { return std::uint64_t{1} << (sequence & 63); }

  bool test(std::uint64_t sequence) const noexcept { return (words_[word_of(sequence)] & bit_of(sequence)) != 0; }
  void set(std::uint64_t sequence) noexcept { words_[word_of(sequence)] |= bit_of(sequence); }

  // Clears the words that will hold numbers in (newest_, sequence]: they still hold numbers kWords * 64 older.
  void advance_to(std::uint64_t sequence) noexcept {
    const std::uint64_t from = newest_ >> 6;
    const std::uint64_t to = sequence >> 6;
    if (to - from >= kWords) {
      words_.fill(0);
      return;
    }
    for (std::uint64_t word = from + 1; word <= to; ++word) words_[static_cast<std::size_t>(word % kWords)] = 0;
  }

  std::array<std::uint64_t, kWords> words_{};
  std::uint64_t newest_ = 0;
  bool started_ = false;
};

}  // namespace lever::bridge
