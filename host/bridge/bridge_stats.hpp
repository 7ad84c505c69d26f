#pragma once
// What a bridge counts, and the periodic JSON line made of it. Counters only grow; rates are per interval.
#include <array>
#include <cstdint>
#include <nlohmann/json.hpp>
#include <optional>

namespace lever::bridge {

// Latencies in logarithmic buckets (about 5 % wide, 1 us to 10 s): percentiles without storing samples.
class LatencyHistogram {
 public:
  void add(std::int64_t us) noexcept;
  void clear() noexcept { *this = {}; }
  std::uint64_t count() const noexcept { return count_; }
  std::optional<double> percentile(double q) const noexcept;  // microseconds
  std::int64_t max() const noexcept { return max_; }

 private:
  static constexpr std::size_t kBuckets = 340;
  std::array<std::uint32_t, kBuckets> buckets_{};
  std::uint64_t count_ = 0;
  std::int64_t max_ = 0;
};

struct DirectionCounters {
  std::uint64_t frames = 0;      // CAN frames relayed
  std::uint64_t datagrams = 0;   // data datagrams sent or accepted
  std::uint64_t disallowed = 0;  // frames the allow-list stopped
};

struct BridgeCounters {
  DirectionCounters to_network, from_network;
  std::uint64_t send_failures = 0;     // sendto failed (no route, buffer full)
  std::uint64_t peer_unreachable = 0;  // ICMP reports that the peer's address or port does not answer
  std::uint64_t auth_failures = 0;     // bad tag: forged, tampered, wrong key
  std::uint64_t malformed = 0;         // any other decode error (truncated, oversized, bad fields, not ours)
  std::uint64_t foreign_source = 0;    // from an address other than the peer
  std::uint64_t reflected = 0;         // carrying our own site id
  std::uint64_t wrong_site = 0;        // carrying a site id other than the configured peer's
  std::uint64_t stale = 0;             // authentic and new, but not echoing our epoch: sent before our start
  std::uint64_t peer_epochs = 0;       // times the peer's epoch was learned (first contact, then its restarts)
  std::uint64_t duplicates = 0;        // replay window: seen before
  std::uint64_t too_old = 0;           // replay window: behind the window
  std::uint64_t reordered = 0;         // accepted, but older than the newest
  std::uint64_t sequence_gaps = 0;     // sequence numbers skipped (lost or still to come)
  std::uint64_t can_down_drops = 0;    // frames from the network dropped while the CAN interface was down
  std::uint64_t can_tx_full = 0;       // frames from the network the CAN queue refused
  std::uint64_t can_reopens = 0;       // the interface came back
  std::uint64_t probes_sent = 0, probe_replies = 0;
};

struct ClockEstimate {
  std::optional<std::int64_t> round_trip_us;
  std::optional<std::int64_t> offset_us;  // peer's steady clock minus ours
};

}  // namespace lever::bridge
