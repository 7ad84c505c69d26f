#pragma once
// What a bridge counts, and the periodic JSON line made of it. Counters only grow; rates are per interval.
//
// Threads: each relay thread writes its own counters and the housekeeping thread reads them all (relay.hpp). No
// lock anywhere: a counter one thread writes is a relaxed load and store (Counter), one that several threads write
// a relaxed fetch_add (SharedCounter); the two relay threads' counters sit on cache lines of their own.
#include <array>
#include <atomic>
#include <cstdint>
#include <nlohmann/json.hpp>
#include <optional>

namespace lever::bridge {

// Latencies in logarithmic buckets (about 5 % wide, 1 us to 10 s): percentiles without storing samples.
class LatencyHistogram {
 public:
  static constexpr std::size_t kBuckets = 340;
  static std::size_t bucket_of(std::int64_t us) noexcept;

  void add(std::int64_t us) noexcept;
  void add_to_bucket(std::size_t bucket, std::uint64_t n) noexcept;
  void note_max(std::int64_t us) noexcept {
    if (us > max_) max_ = us;
  }
  void clear() noexcept { *this = {}; }
  std::uint64_t count() const noexcept { return count_; }
  std::optional<double> percentile(double q) const noexcept;  // microseconds
  std::int64_t max() const noexcept { return max_; }

 private:
  std::array<std::uint64_t, kBuckets> buckets_{};
  std::uint64_t count_ = 0;
  std::int64_t max_ = 0;
};

// A histogram one thread adds to while another takes an interval's worth: the adder owns cumulative bucket
// totals (a relaxed load and store each), the taker keeps the totals it last saw and takes the difference; the
// interval's maximum is the one value both write (the taker resets it), by compare-and-swap, and only when a
// sample beats it.
class SharedLatencyHistogram {
 public:
  void add(std::int64_t us) noexcept;         // one thread
  LatencyHistogram take_interval() noexcept;  // one other thread

 private:
  std::array<std::atomic<std::uint64_t>, LatencyHistogram::kBuckets> totals_{};
  std::array<std::uint64_t, LatencyHistogram::kBuckets> taken_{};
  std::atomic<std::int64_t> max_{0};
};

// Written by one thread, read by any.
class Counter {
 public:
  Counter() = default;
  Counter(const Counter& other) noexcept : value_(other.load()) {}
  Counter& operator=(const Counter& other) noexcept {
    value_.store(other.load(), std::memory_order_relaxed);
    return *this;
  }
  Counter& operator+=(std::uint64_t n) noexcept {
    value_.store(value_.load(std::memory_order_relaxed) + n, std::memory_order_relaxed);
    return *this;
  }
  Counter& operator++() noexcept { return *this += 1; }
  std::uint64_t load() const noexcept { return value_.load(std::memory_order_relaxed); }

 private:
  std::atomic<std::uint64_t> value_{0};
};

// Written by several threads.
class SharedCounter {
 public:
  SharedCounter() = default;
  SharedCounter(const SharedCounter& other) noexcept : value_(other.load()) {}
  SharedCounter& operator=(const SharedCounter& other) noexcept {
    value_.store(other.load(), std::memory_order_relaxed);
    return *this;
  }
  SharedCounter& operator+=(std::uint64_t n) noexcept {
    value_.fetch_add(n, std::memory_order_relaxed);
    return *this;
  }
  SharedCounter& operator++() noexcept { return *this += 1; }
  std::uint64_t load() const noexcept { return value_.load(std::memory_order_relaxed); }

 private:
  std::atomic<std::uint64_t> value_{0};
};

struct DirectionCounters {
  Counter frames;      // CAN frames relayed
  Counter datagrams;   // data datagrams sent or accepted
  Counter disallowed;  // frames the allow-list stopped
};

inline constexpr std::size_t kCacheLine = 64;

struct BridgeCounters {
  // The CAN -> network thread's.
  DirectionCounters to_network;
  // The network -> CAN thread's.
  alignas(kCacheLine) DirectionCounters from_network;
  Counter peer_unreachable;  // ICMP reports that the peer's address or port does not answer
  Counter auth_failures;     // bad tag: forged, tampered, wrong key
  Counter malformed;         // any other decode error (truncated, oversized, bad fields, not ours)
  Counter foreign_source;    // from an address other than the peer
  Counter reflected;         // carrying our own site id
  Counter wrong_site;        // carrying a site id other than the configured peer's
  Counter stale;             // authentic and new, but not echoing our epoch: sent before our start
  Counter peer_epochs;       // times the peer's epoch was learned (first contact, then its restarts)
  Counter duplicates;        // replay window: seen before
  Counter too_old;           // replay window: behind the window
  Counter reordered;         // accepted, but older than the newest
  Counter sequence_gaps;     // sequence numbers skipped (lost or still to come)
  Counter can_down_drops;    // frames from the network dropped while the CAN interface was down
  Counter can_tx_full;       // frames from the network the CAN queue refused
  Counter probe_replies;
  // Any thread sends (data, probes, probe replies).
  alignas(kCacheLine) SharedCounter send_failures;  // sendto failed (no route, buffer full)
  SharedCounter probes_sent;
  // The housekeeping thread's.
  Counter can_reopens;  // the interface came back
};

struct ClockEstimate {
  std::optional<std::int64_t> round_trip_us;
  std::optional<std::int64_t> offset_us;  // peer's steady clock minus ours
};

}  // namespace lever::bridge
