// libFuzzer harness for lever::bridge::decode (docs/datagram-format.md).
//
// Random bytes almost never carry a valid HMAC, so each input is decoded twice: as it is (the paths before the
// tag: lengths, magic, version, the tag check itself) and re-signed with the fuzz key (every path after the tag).
// Beyond "no crash, no sanitizer report", it checks invariants and aborts when one breaks:
//   - the verdict before the tag follows from length, magic and version alone;
//   - bad_tag exactly when the tag is not the HMAC of the bytes before it;
//   - a failed decode leaves Datagram{};
//   - a decoded datagram is in range and re-encodes to the very same bytes (the encoding is canonical);
//   - the precomputed key state (MacKey, the relay's) gives the same verdict and the same datagram.
#include <sodium.h>

#include <array>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <span>

#include "datagram.hpp"
#include "fuzz_key.hpp"

namespace {

using namespace lever::bridge;

[[noreturn]] void fail(const char* what, WireError error, std::size_t size) {
  std::fprintf(stderr, "datagram fuzzer: invariant broken: %s (decode gave %s, %zu bytes)\n", what, to_string(error),
               size);
  std::abort();
}

#define LEVER_FUZZ_CHECK(condition, error, size)     \
  do {                                               \
    if (!(condition)) fail(#condition, error, size); \
  } while (0)

bool is_empty(const Datagram& d) {
  const Datagram empty{};
  if (d.kind != empty.kind || d.sender != 0 || d.sequence != 0 || d.timestamp_us != 0 || d.epoch != 0 ||
      d.peer_epoch != 0 || d.frame_count != 0 || !(d.echo == empty.echo)) {
    return false;
  }
  for (const auto& f : d.frames) {
    if (f.id != 0 || f.dlc != 0) return false;
    for (const auto b : f.data) {
      if (b != 0) return false;
    }
  }
  return true;
}

// Field by field: a frame's padding bytes are not part of its value.
bool same_frames(const Datagram& a, const Datagram& b) {
  for (std::size_t i = 0; i < kMaxFrames; ++i) {
    if (a.frames[i].id != b.frames[i].id || a.frames[i].dlc != b.frames[i].dlc || a.frames[i].data != b.frames[i].data)
      return false;
  }
  return true;
}

bool tag_matches(std::span<const std::uint8_t> in, const Key& key) {
  if (in.size() < kTagSize) return false;
  std::array<std::uint8_t, kTagSize> tag{};
  const std::size_t n = in.size() - kTagSize;
  crypto_auth_hmacsha512256(tag.data(), in.data(), n, key.bytes.data());
  return std::memcmp(tag.data(), in.data() + n, kTagSize) == 0;
}

// Decodes `in` and checks every invariant; returns the verdict.
WireError check(std::span<const std::uint8_t> in, const Key& key) {
  Datagram out;
  out.sequence = 42;  // decode must overwrite everything, also on error
  const WireError error = decode(in, key, out);
  const std::size_t size = in.size();

  static const MacKey mac_key(key);
  Datagram precomputed;
  precomputed.sequence = 42;
  const WireError with_state = decode(in, mac_key, precomputed);
  LEVER_FUZZ_CHECK(with_state == error, error, size);
  LEVER_FUZZ_CHECK(precomputed.sequence == out.sequence && precomputed.frame_count == out.frame_count &&
                       same_frames(precomputed, out),
                   error, size);

  // Before the tag: length, magic and version decide alone.
  if (size < 3) {
    LEVER_FUZZ_CHECK(error == WireError::truncated, error, size);
  } else if (in[0] != kMagic0 || in[1] != kMagic1) {
    LEVER_FUZZ_CHECK(error == WireError::bad_magic, error, size);
  } else if (in[2] != kVersion) {
    LEVER_FUZZ_CHECK(error == WireError::bad_version, error, size);
  } else if (size < kMinDatagramSize) {
    LEVER_FUZZ_CHECK(error == WireError::truncated, error, size);
  } else if (size > kMaxDatagramSize) {
    LEVER_FUZZ_CHECK(error == WireError::oversized, error, size);
  } else {
    LEVER_FUZZ_CHECK((error == WireError::bad_tag) == !tag_matches(in, key), error, size);
  }
  LEVER_FUZZ_CHECK(error != WireError::buffer_too_small, error, size);

  if (error != WireError::none) {
    LEVER_FUZZ_CHECK(is_empty(out), error, size);
    return error;
  }

  // A decoded datagram is in range, zero beyond each dlc, and re-encodes to the same bytes.
  LEVER_FUZZ_CHECK(out.frame_count <= kMaxFrames, error, size);
  LEVER_FUZZ_CHECK(out.kind == Kind::data || out.frame_count == 0, error, size);
  LEVER_FUZZ_CHECK(out.kind != Kind::probe_request || out.echo == ProbeEcho{}, error, size);
  for (std::size_t i = 0; i < out.frame_count; ++i) {
    const auto& f = out.frames[i];
    LEVER_FUZZ_CHECK(f.id <= lever::protocol::kMaxStandardId, error, size);
    LEVER_FUZZ_CHECK(f.dlc <= kMaxDlc, error, size);
    for (std::size_t b = f.dlc; b < f.data.size(); ++b) LEVER_FUZZ_CHECK(f.data[b] == 0, error, size);
  }
  LEVER_FUZZ_CHECK(encoded_size(out) == size, error, size);
  std::array<std::uint8_t, kMaxDatagramSize> again{};
  const auto encoded = encode(out, key, again);
  LEVER_FUZZ_CHECK(encoded.error == WireError::none, encoded.error, size);
  LEVER_FUZZ_CHECK(encoded.size == size, error, size);
  LEVER_FUZZ_CHECK(std::memcmp(again.data(), in.data(), size) == 0, error, size);
  // The clock arithmetic takes any timestamps a peer can send (UBSan watches the signed arithmetic).
  if (out.kind == Kind::probe_reply) {
    const auto timing = probe_timing(out, out.echo.receive_timestamp_us ^ out.sequence);
    LEVER_FUZZ_CHECK(
        timing.round_trip_us ==
            static_cast<std::int64_t>((out.echo.receive_timestamp_us ^ out.sequence) - out.echo.request_timestamp_us -
                                      out.timestamp_us + out.echo.receive_timestamp_us),
        error, size);
  }
  return error;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const Key key = lever::bridge::fuzz::fuzz_key();
  const std::span<const std::uint8_t> in(data, size);
  check(in, key);

  // The same bytes made authentic: everything after the tag check is reached.
  if (size >= kMinDatagramSize && size <= kMaxDatagramSize) {
    std::array<std::uint8_t, kMaxDatagramSize> signed_copy{};
    std::memcpy(signed_copy.data(), data, size);
    const std::size_t n = size - kTagSize;
    crypto_auth_hmacsha512256(signed_copy.data() + n, signed_copy.data(), n, key.bytes.data());
    const WireError error = check(std::span<const std::uint8_t>(signed_copy.data(), size), key);
    LEVER_FUZZ_CHECK(error != WireError::bad_tag, error, size);
  }
  return 0;
}
