#pragma once
// The lever-bridge UDP datagram: CAN frames (or a clock probe) between two sites, authenticated with
// HMAC-SHA-512-256. The one written spec is docs/datagram-format.md; this is its only implementation.
//
// encode() and decode() never throw, never allocate and never read or write outside the spans they are given:
// the decoder checks the length before every read, assembles every integer byte by byte in network order, and
// verifies the tag (constant time, libsodium) before it looks at anything but the magic and the version.
// Errors are WireError codes with stable numbers: a bridge counts them per code.
#include <array>
#include <cstddef>
#include <cstdint>
#include <span>

#include "key.hpp"
#include "lever/protocol/can_frame.hpp"

namespace lever::bridge {

// ---- Sizes (docs/datagram-format.md, "Layout") ----
inline constexpr std::uint8_t kMagic0 = 0x4C;  // 'L'
inline constexpr std::uint8_t kMagic1 = 0x42;  // 'B'
inline constexpr std::uint8_t kVersion = 2;    // 2: the epochs (docs/datagram-format.md, "Restarts")
// magic, version, flags, sender, count, sequence, timestamp, epoch, peer epoch
inline constexpr std::size_t kHeaderSize = 38;
inline constexpr std::size_t kTagSize = 32;  // crypto_auth_hmacsha512256_BYTES
inline constexpr std::size_t kMaxFrames = 32;
inline constexpr std::size_t kFrameHeaderSize = 3;  // id (2), dlc (1)
inline constexpr std::size_t kMaxDlc = 8;           // classic CAN
inline constexpr std::size_t kMaxFrameSize = kFrameHeaderSize + kMaxDlc;
inline constexpr std::size_t kProbeBodySize = 24;  // echo sequence, echo timestamp, receive timestamp
inline constexpr std::size_t kMinDatagramSize = kHeaderSize + kTagSize;                               // 70
inline constexpr std::size_t kProbeDatagramSize = kHeaderSize + kProbeBodySize + kTagSize;            // 94
inline constexpr std::size_t kMaxDatagramSize = kHeaderSize + kMaxFrames * kMaxFrameSize + kTagSize;  // 422
static_assert(kMaxDatagramSize == 422 && kMaxDatagramSize < 1200);

// Flags byte (offset 3).
inline constexpr std::uint8_t kFlagProbe = 0x01;
inline constexpr std::uint8_t kFlagReply = 0x02;  // only with kFlagProbe
inline constexpr std::uint8_t kFlagsReserved = 0xFC;

// Stable numbers: counted per code by the bridge and named in its statistics. Never renumber; append.
enum class WireError : std::uint8_t {
  none = 0,
  truncated = 1,          // shorter than the smallest datagram, or (authentic) content runs past the tag
  oversized = 2,          // longer than kMaxDatagramSize
  bad_magic = 3,          // not a lever-bridge datagram
  bad_version = 4,        // another version of this format
  bad_tag = 5,            // authentication failed: corrupted, forged, or another key
  bad_flags = 6,          // a reserved flag bit set, or reply without probe
  bad_frame_count = 7,    // more than kMaxFrames, or a probe carrying frames
  bad_id = 8,             // id field above 0x7FF (its reserved upper bits set)
  bad_dlc = 9,            // dlc above 8
  trailing_bytes = 10,    // (authentic) bytes left between the content and the tag
  bad_probe = 11,         // a probe request whose echo fields are not zero
  buffer_too_small = 12,  // encode only: the output span cannot hold the datagram
};

// The name of the enumerator ("bad_tag"), for logs and statistics; "unknown" for values not listed.
const char* to_string(WireError error) noexcept;

enum class Kind : std::uint8_t {
  data = 0,           // CAN frames (possibly none: a keep-alive)
  probe_request = 1,  // flags = probe
  probe_reply = 2,    // flags = probe | reply
};

// A probe reply's echo: NTP-style timestamps t1 (the request's timestamp) and t2 (when the request arrived, on
// the replier's clock); the reply's own header timestamp is t3. All zero in a request.
struct ProbeEcho {
  std::uint64_t sequence = 0;              // the request's sequence number
  std::uint64_t request_timestamp_us = 0;  // t1, the requester's clock
  std::uint64_t receive_timestamp_us = 0;  // t2, the replier's clock
  friend bool operator==(const ProbeEcho&, const ProbeEcho&) = default;
};

// One datagram, as encode() takes it and decode() fills it.
struct Datagram {
  Kind kind = Kind::data;
  std::uint8_t sender = 0;         // the sending site's id; a receiver rejects its own id (reflection)
  std::uint64_t sequence = 0;      // per sender and key, never reused; see replay_window.hpp
  std::uint64_t timestamp_us = 0;  // sender's steady clock when sent, microseconds
  std::uint64_t epoch = 0;         // the sender's epoch: random, drawn at start, never 0 (peer_session.hpp)
  std::uint64_t peer_epoch = 0;    // the receiver's epoch as the sender last learned it; 0: none yet
  std::size_t frame_count = 0;     // data only, 0..kMaxFrames
  std::array<protocol::CanFrame, kMaxFrames> frames{};  // decode() zeroes data bytes beyond each dlc
  ProbeEcho echo{};                                     // probe_reply only

  std::span<const protocol::CanFrame> frame_list() const noexcept {
    return {frames.data(), frame_count <= kMaxFrames ? frame_count : kMaxFrames};
  }
};

struct EncodeResult {
  WireError error = WireError::none;
  std::size_t size = 0;  // bytes written, when error == none
  explicit operator bool() const noexcept { return error == WireError::none; }
};

// The encoded size of a valid datagram (frame_count clamped to kMaxFrames, dlc to 8).
std::size_t encoded_size(const Datagram& datagram) noexcept;

// Encodes and authenticates `datagram` into the front of `out`. Validates first (frame count, id, dlc, kind,
// zero echo in a request, room in `out`) and writes nothing on error. Only the first dlc data bytes of each
// frame are sent.
[[nodiscard]] EncodeResult encode(const Datagram& datagram, const Key& key, std::span<std::uint8_t> out) noexcept;
// The same with the key's HMAC state computed beforehand (key.hpp): what the relay uses on every datagram.
[[nodiscard]] EncodeResult encode(const Datagram& datagram, const MacKey& key, std::span<std::uint8_t> out) noexcept;

// Decodes one received datagram (the whole of `in`; receive into a buffer larger than kMaxDatagramSize so an
// oversized datagram is seen as such, not cut). Checks, in this order: length at least 3, magic, version, length
// within [kMinDatagramSize, kMaxDatagramSize], the tag; only then flags, count, frames and probe fields.
// On success `out` holds the datagram; on error `out` is reset to Datagram{}.
// Authenticity is not freshness: pass the datagram to a PeerSession (peer_session.hpp) afterwards.
[[nodiscard]] WireError decode(std::span<const std::uint8_t> in, const Key& key, Datagram& out) noexcept;
[[nodiscard]] WireError decode(std::span<const std::uint8_t> in, const MacKey& key, Datagram& out) noexcept;

// ---- Probes (docs/datagram-format.md, "Probe") ----

// The reply to `request`, to be stamped and sent by the replier: `receive_us` is t2 (request arrival),
// `send_us` is t3 (now, just before encoding), both on the replier's clock.
Datagram make_probe_reply(const Datagram& request, std::uint8_t sender, std::uint64_t sequence,
                          std::uint64_t receive_us, std::uint64_t send_us) noexcept;

struct ProbeTiming {
  std::int64_t round_trip_us = 0;  // (t4 - t1) - (t3 - t2): network time, without the replier's turnaround
  std::int64_t offset_us = 0;      // ((t2 - t1) + (t3 - t4)) / 2: replier's clock minus requester's clock
};

// What a reply says, given t4 (`arrival_us`, when it arrived, on the requester's clock).
ProbeTiming probe_timing(const Datagram& reply, std::uint64_t arrival_us) noexcept;

}  // namespace lever::bridge
