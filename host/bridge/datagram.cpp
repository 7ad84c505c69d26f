// The datagram codec (docs/datagram-format.md). No heap, no exceptions, no OS: the only calls out are
// libsodium's HMAC and memcpy/memset (tests/bridge/check_wire_symbols.sh proves it on the object file).
#include "datagram.hpp"

#include <sodium.h>

#include <atomic>

namespace lever::bridge {

static_assert(kTagSize == crypto_auth_hmacsha512256_BYTES);
static_assert(kKeySize == crypto_auth_hmacsha512256_KEYBYTES);

namespace {

// sodium_init() is idempotent and thread-safe but takes a lock; remember that it ran. Constant-initialised, so
// no guard variable (and no __cxa_guard_* in the object).
std::atomic<bool> sodium_ready{false};

void ensure_sodium() noexcept {
  if (!sodium_ready.load(std::memory_order_acquire)) {
    // The HMAC needs no randomness, so a failure here (no RNG) does not stop encode/decode.
    [[maybe_unused]] const int status = sodium_init();
    sodium_ready.store(true, std::memory_order_release);
  }
}

// Writes big-endian integers into a span; encode() has checked the size, but every write checks again.
class Writer {
 public:
  explicit Writer(std::span<std::uint8_t> out) noexcept : out_(out) {}
  void u8(std::uint8_t v) noexcept {
    if (pos_ < out_.size()) out_[pos_] = v;
    ++pos_;
  }
  void u16(std::uint16_t v) noexcept {
    u8(static_cast<std::uint8_t>(v >> 8));
    u8(static_cast<std::uint8_t>(v));
  }
  void u64(std::uint64_t v) noexcept {
    for (int shift = 56; shift >= 0; shift -= 8) u8(static_cast<std::uint8_t>(v >> shift));
  }
  std::size_t position() const noexcept { return pos_; }

 private:
  std::span<std::uint8_t> out_;
  std::size_t pos_ = 0;
};

// Reads big-endian integers from a span; each read checks that its bytes are there and fails otherwise.
class Reader {
 public:
  explicit Reader(std::span<const std::uint8_t> in) noexcept : in_(in) {}
  bool u8(std::uint8_t& v) noexcept {
    if (remaining() < 1) return false;
    v = in_[pos_++];
    return true;
  }
  bool u16(std::uint16_t& v) noexcept {
    if (remaining() < 2) return false;
    v = static_cast<std::uint16_t>(in_[pos_] << 8 | in_[pos_ + 1]);
    pos_ += 2;
    return true;
  }
  bool u64(std::uint64_t& v) noexcept {
    if (remaining() < 8) return false;
    v = 0;
    for (std::size_t i = 0; i < 8; ++i) v = v << 8 | in_[pos_ + i];
    pos_ += 8;
    return true;
  }
  std::size_t remaining() const noexcept { return in_.size() - pos_; }

 private:
  std::span<const std::uint8_t> in_;
  std::size_t pos_ = 0;
};

std::uint8_t flags_of(Kind kind) noexcept {
  switch (kind) {
    case Kind::data:
      return 0;
    case Kind::probe_request:
      return kFlagProbe;
    case Kind::probe_reply:
      return kFlagProbe | kFlagReply;
  }
  return 0xFF;  // not a Kind: validate() has refused it
}

bool is_zero(const ProbeEcho& echo) noexcept { return echo == ProbeEcho{}; }

WireError validate(const Datagram& d) noexcept {
  switch (d.kind) {
    case Kind::data:
      if (d.frame_count > kMaxFrames) return WireError::bad_frame_count;
      for (std::size_t i = 0; i < d.frame_count; ++i) {
        if (d.frames[i].id > protocol::kMaxStandardId) return WireError::bad_id;
        if (d.frames[i].dlc > kMaxDlc) return WireError::bad_dlc;
      }
      return WireError::none;
    case Kind::probe_request:
      if (d.frame_count != 0) return WireError::bad_frame_count;
      if (!is_zero(d.echo)) return WireError::bad_probe;
      return WireError::none;
    case Kind::probe_reply:
      if (d.frame_count != 0) return WireError::bad_frame_count;
      return WireError::none;
  }
  return WireError::bad_flags;
}

// Everything after the tag check. `body` is the authenticated bytes after the header (the tag excluded).
WireError decode_body(std::uint8_t flags, std::uint8_t count, std::span<const std::uint8_t> body,
                      Datagram& out) noexcept {
  if ((flags & kFlagsReserved) != 0) return WireError::bad_flags;
  const bool probe = (flags & kFlagProbe) != 0;
  const bool reply = (flags & kFlagReply) != 0;
  if (reply && !probe) return WireError::bad_flags;
  if (count > kMaxFrames || (probe && count != 0)) return WireError::bad_frame_count;

  Reader reader(body);
  if (probe) {
    out.kind = reply ? Kind::probe_reply : Kind::probe_request;
    if (!reader.u64(out.echo.sequence) || !reader.u64(out.echo.request_timestamp_us) ||
        !reader.u64(out.echo.receive_timestamp_us)) {
      return WireError::truncated;
    }
    if (!reply && !is_zero(out.echo)) return WireError::bad_probe;
  } else {
    out.kind = Kind::data;
    for (std::size_t i = 0; i < count; ++i) {
      auto& frame = out.frames[i];
      std::uint16_t id = 0;
      std::uint8_t dlc = 0;
      if (!reader.u16(id) || !reader.u8(dlc)) return WireError::truncated;
      if (id > protocol::kMaxStandardId) return WireError::bad_id;
      if (dlc > kMaxDlc) return WireError::bad_dlc;
      frame.id = id;
      frame.dlc = dlc;
      for (std::size_t b = 0; b < dlc; ++b) {
        if (!reader.u8(frame.data[b])) return WireError::truncated;
      }
    }
    out.frame_count = count;
  }
  if (reader.remaining() != 0) return WireError::trailing_bytes;
  return WireError::none;
}

}  // namespace

const char* to_string(WireError error) noexcept {
  switch (error) {
    case WireError::none:
      return "none";
    case WireError::truncated:
      return "truncated";
    case WireError::oversized:
      return "oversized";
    case WireError::bad_magic:
      return "bad_magic";
    case WireError::bad_version:
      return "bad_version";
    case WireError::bad_tag:
      return "bad_tag";
    case WireError::bad_flags:
      return "bad_flags";
    case WireError::bad_frame_count:
      return "bad_frame_count";
    case WireError::bad_id:
      return "bad_id";
    case WireError::bad_dlc:
      return "bad_dlc";
    case WireError::trailing_bytes:
      return "trailing_bytes";
    case WireError::bad_probe:
      return "bad_probe";
    case WireError::buffer_too_small:
      return "buffer_too_small";
  }
  return "unknown";
}

std::size_t encoded_size(const Datagram& d) noexcept {
  if (d.kind != Kind::data) return kProbeDatagramSize;
  std::size_t size = kHeaderSize + kTagSize;
  const std::size_t count = d.frame_count <= kMaxFrames ? d.frame_count : kMaxFrames;
  for (std::size_t i = 0; i < count; ++i) {
    size += kFrameHeaderSize + (d.frames[i].dlc <= kMaxDlc ? d.frames[i].dlc : kMaxDlc);
  }
  return size;
}

namespace {

// Everything of encode() but the tag: returns the datagram's size, the tag's bytes left for the caller.
EncodeResult encode_untagged(const Datagram& d, std::span<std::uint8_t> out) noexcept {
  if (const auto error = validate(d); error != WireError::none) return {error, 0};
  const std::size_t size = encoded_size(d);
  if (out.size() < size) return {WireError::buffer_too_small, 0};

  Writer writer(out.first(size - kTagSize));
  writer.u8(kMagic0);
  writer.u8(kMagic1);
  writer.u8(kVersion);
  writer.u8(flags_of(d.kind));
  writer.u8(d.sender);
  writer.u8(static_cast<std::uint8_t>(d.frame_count));
  writer.u64(d.sequence);
  writer.u64(d.timestamp_us);
  writer.u64(d.epoch);
  writer.u64(d.peer_epoch);
  if (d.kind == Kind::data) {
    for (std::size_t i = 0; i < d.frame_count; ++i) {
      const auto& frame = d.frames[i];
      writer.u16(static_cast<std::uint16_t>(frame.id));
      writer.u8(frame.dlc);
      for (std::size_t b = 0; b < frame.dlc; ++b) writer.u8(frame.data[b]);
    }
  } else {
    writer.u64(d.echo.sequence);
    writer.u64(d.echo.request_timestamp_us);
    writer.u64(d.echo.receive_timestamp_us);
  }
  if (writer.position() != size - kTagSize) return {WireError::buffer_too_small, 0};  // unreachable
  return {WireError::none, size};
}

// The tag of `message` under the precomputed state. final() hashes through a copy, and libsodium's SHA-512 final
// wipes the states it finishes, so no key-derived bytes are left on the stack.
void tag_of(const MacKey& key, std::span<const std::uint8_t> message, std::uint8_t* tag) noexcept {
  crypto_auth_hmacsha512256_state state = key.state();
  crypto_auth_hmacsha512256_update(&state, message.data(), message.size());
  crypto_auth_hmacsha512256_final(&state, tag);
}

// The checks decode() makes before the tag; none means the length is that of a possible datagram.
WireError check_before_tag(std::span<const std::uint8_t> in) noexcept {
  if (in.size() < 3) return WireError::truncated;
  if (in[0] != kMagic0 || in[1] != kMagic1) return WireError::bad_magic;
  if (in[2] != kVersion) return WireError::bad_version;
  if (in.size() < kMinDatagramSize) return WireError::truncated;
  if (in.size() > kMaxDatagramSize) return WireError::oversized;
  return WireError::none;
}

WireError decode_authentic(std::span<const std::uint8_t> in, Datagram& out) noexcept {
  const std::size_t authenticated = in.size() - kTagSize;
  // Authentic from here on; still checked field by field, since a peer with the key can have a bug.
  Reader header(in.first(kHeaderSize));
  std::uint8_t ignored = 0;
  std::uint8_t flags = 0;
  std::uint8_t count = 0;
  const bool complete = header.u8(ignored) && header.u8(ignored) && header.u8(ignored) && header.u8(flags) &&
                        header.u8(out.sender) && header.u8(count) && header.u64(out.sequence) &&
                        header.u64(out.timestamp_us) && header.u64(out.epoch) && header.u64(out.peer_epoch);
  WireError error = complete ? WireError::none : WireError::truncated;  // complete: the length was checked
  if (error == WireError::none) {
    error = decode_body(flags, count, in.subspan(kHeaderSize, authenticated - kHeaderSize), out);
  }
  if (error != WireError::none) out = Datagram{};
  return error;
}

}  // namespace

EncodeResult encode(const Datagram& d, const Key& key, std::span<std::uint8_t> out) noexcept {
  const auto result = encode_untagged(d, out);
  if (!result) return result;
  ensure_sodium();
  const std::size_t authenticated = result.size - kTagSize;
  crypto_auth_hmacsha512256(out.data() + authenticated, out.data(), authenticated, key.bytes.data());
  return result;
}

EncodeResult encode(const Datagram& d, const MacKey& key, std::span<std::uint8_t> out) noexcept {
  const auto result = encode_untagged(d, out);
  if (!result) return result;
  const std::size_t authenticated = result.size - kTagSize;
  tag_of(key, out.first(authenticated), out.data() + authenticated);
  return result;
}

WireError decode(std::span<const std::uint8_t> in, const Key& key, Datagram& out) noexcept {
  out = Datagram{};
  // Before the tag: only what is needed to know this is our format, in this version, of a possible size.
  if (const auto error = check_before_tag(in); error != WireError::none) return error;
  ensure_sodium();
  const std::size_t authenticated = in.size() - kTagSize;
  if (crypto_auth_hmacsha512256_verify(in.data() + authenticated, in.data(), authenticated, key.bytes.data()) != 0) {
    return WireError::bad_tag;
  }
  return decode_authentic(in, out);
}

WireError decode(std::span<const std::uint8_t> in, const MacKey& key, Datagram& out) noexcept {
  out = Datagram{};
  if (const auto error = check_before_tag(in); error != WireError::none) return error;
  const std::size_t authenticated = in.size() - kTagSize;
  std::array<std::uint8_t, kTagSize> expected;
  tag_of(key, in.first(authenticated), expected.data());
  // Constant time, as crypto_auth_hmacsha512256_verify compares.
  if (crypto_verify_32(expected.data(), in.data() + authenticated) != 0) return WireError::bad_tag;
  return decode_authentic(in, out);
}

Datagram make_probe_reply(const Datagram& request, std::uint8_t sender, std::uint64_t sequence,
                          std::uint64_t receive_us, std::uint64_t send_us) noexcept {
  Datagram reply;
  reply.kind = Kind::probe_reply;
  reply.sender = sender;
  reply.sequence = sequence;
  reply.timestamp_us = send_us;
  reply.echo = {request.sequence, request.timestamp_us, receive_us};
  return reply;
}

ProbeTiming probe_timing(const Datagram& reply, std::uint64_t arrival_us) noexcept {
  const std::uint64_t t1 = reply.echo.request_timestamp_us;
  const std::uint64_t t2 = reply.echo.receive_timestamp_us;
  const std::uint64_t t3 = reply.timestamp_us;
  const std::uint64_t t4 = arrival_us;
  // Differences of one clock's readings wrap modulo 2^64 like the clocks. The offset is (outbound + inbound) / 2
  // rounded toward zero, without the sum (which can overflow 64 bits; 32-bit Arm has no 128-bit integer): the floor
  // of the half sum by halves (arithmetic shifts), then one up where the sum is odd and negative.
  const auto round_trip = static_cast<std::int64_t>((t4 - t1) - (t3 - t2));
  const auto outbound = static_cast<std::int64_t>(t2 - t1);
  const auto inbound = static_cast<std::int64_t>(t3 - t4);
  const std::int64_t floor_half = (outbound >> 1) + (inbound >> 1) + (outbound & inbound & 1);
  const bool odd = ((outbound ^ inbound) & 1) != 0;
  const std::int64_t offset = floor_half + (odd && floor_half < 0 ? 1 : 0);
  return {round_trip, offset};
}

}  // namespace lever::bridge
