#pragma once
// What a bridge knows of its peer across restarts of either end: its own epoch (a random number drawn at start),
// the peer's epoch as last learned, and the replay window over the peer's sequence numbers. It decides whether an
// authentic datagram is fresh, that is, sent by the peer after it heard from this very run of the bridge.
//
// Why: the replay window starts empty in a restarted bridge, so on its own it would take datagrams recorded before
// the restart. Every datagram carries the sender's epoch and echoes the receiver's (docs/datagram-format.md,
// "Restarts"); a receiver acts only on datagrams that echo its current epoch, which no datagram sent before the
// epoch was drawn can do. Heap-free, no exceptions, no clock.
#include <cstdint>

#include "replay_window.hpp"

namespace lever::bridge {

enum class Admission : std::uint8_t {
  fresh = 0,      // authentic, new, and echoes our epoch: act on it
  stale = 1,      // authentic and new, but echoes another epoch (or none): sent before the peer heard from us
  duplicate = 2,  // replay window: seen before
  too_old = 3,    // replay window: too far behind the newest
};

struct AdmissionResult {
  Admission admission = Admission::fresh;
  ReplayResult replay{};            // the window's verdict, gaps and reordering included
  bool peer_epoch_changed = false;  // this datagram taught us a new peer epoch (the peer restarted, or first contact)

  bool fresh() const noexcept { return admission == Admission::fresh; }
};

template <std::size_t Width = 1024>
class PeerSession {
 public:
  // `own_epoch`: random and non-zero (generate_epoch() in key.hpp). 0 would match a peer that has learned nothing.
  explicit PeerSession(std::uint64_t own_epoch = 1) noexcept : own_epoch_(own_epoch) {}

  std::uint64_t own_epoch() const noexcept { return own_epoch_; }
  // What to put in outgoing datagrams' peer-epoch field: 0 until a datagram from the peer has been admitted.
  std::uint64_t peer_epoch() const noexcept { return peer_epoch_; }

  // Takes an authentic datagram's sequence number, epoch and echoed peer epoch.
  //
  // The window comes first, for fresh and stale datagrams alike: a stale datagram is still authentic, and the
  // peer's sequence numbers only grow, across its restarts too (they start at its real-time clock), so a stale
  // one never pushes the window past genuine traffic. Only the newest datagram teaches the peer's epoch: a late
  // one, or a replay that reaches a restarted bridge ahead of the peer's live traffic, cannot roll it back
  // once anything newer arrived.
  AdmissionResult admit(std::uint64_t sequence, std::uint64_t epoch, std::uint64_t echoed_epoch) noexcept {
    AdmissionResult result;
    result.replay = window_.accept(sequence);
    if (result.replay.verdict == ReplayVerdict::duplicate) {
      result.admission = Admission::duplicate;
      return result;
    }
    if (result.replay.verdict == ReplayVerdict::too_old) {
      result.admission = Admission::too_old;
      return result;
    }
    if (!result.replay.reordered() && epoch != 0 && epoch != peer_epoch_) {
      peer_epoch_ = epoch;
      result.peer_epoch_changed = true;
    }
    result.admission = echoed_epoch == own_epoch_ ? Admission::fresh : Admission::stale;
    return result;
  }

 private:
  ReplayWindow<Width> window_;
  std::uint64_t own_epoch_;
  std::uint64_t peer_epoch_ = 0;
};

}  // namespace lever::bridge
