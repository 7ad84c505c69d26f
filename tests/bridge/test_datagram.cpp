// The lever-bridge datagram (docs/datagram-format.md): layout to the byte, round trips, and every way a datagram
// is refused. Authentic-but-malformed datagrams are made by re-signing edited bytes with libsodium directly, which
// also proves the tag is HMAC-SHA-512-256 over everything before it, as the spec says.
#include <sodium.h>

#include <algorithm>
#include <array>
#include <catch2/catch.hpp>
#include <cstdint>
#include <limits>
#include <span>
#include <vector>

#include "datagram.hpp"
#include "lever/common/rng.hpp"

using namespace lever::bridge;
using lever::protocol::CanFrame;
using Bytes = std::vector<std::uint8_t>;

namespace {

Key test_key(std::uint8_t first = 1) {
  Key key;
  for (std::size_t i = 0; i < key.bytes.size(); ++i) key.bytes[i] = static_cast<std::uint8_t>(first + 7 * i);
  return key;
}

// Every datagram of these tests is encoded twice, with the one-shot HMAC (Key) and with the precomputed state the
// relay uses (MacKey): the bytes must be the same, so each known answer below holds for both.
Bytes encode_bytes(const Datagram& d, const Key& key) {
  std::array<std::uint8_t, kMaxDatagramSize> buffer{};
  const auto result = encode(d, key, buffer);
  REQUIRE(result.error == WireError::none);
  std::array<std::uint8_t, kMaxDatagramSize> precomputed{};
  const auto again = encode(d, MacKey(key), precomputed);
  REQUIRE(again.error == WireError::none);
  REQUIRE(again.size == result.size);
  CHECK(std::equal(buffer.begin(), buffer.begin() + static_cast<std::ptrdiff_t>(result.size), precomputed.begin()));
  return Bytes(buffer.begin(), buffer.begin() + static_cast<std::ptrdiff_t>(result.size));
}

// Decoded both ways too: the same verdict, and on success the same datagram (compared by its encoding).
WireError decode_bytes(const Bytes& bytes, const Key& key, Datagram& out) {
  Datagram precomputed;
  const auto with_state = decode(bytes, MacKey(key), precomputed);
  const auto error = decode(bytes, key, out);
  CHECK(with_state == error);
  if (error == WireError::none && with_state == WireError::none) {
    std::array<std::uint8_t, kMaxDatagramSize> a{}, b{};
    const auto ea = encode(out, key, a);
    const auto eb = encode(precomputed, key, b);
    CHECK((ea.size == eb.size && std::equal(a.begin(), a.end(), b.begin())));
  }
  return error;
}

WireError decode_bytes(const Bytes& bytes, const Key& key) {
  Datagram out;
  return decode_bytes(bytes, key, out);
}

// Replaces the last 32 bytes with the correct tag of the bytes before them.
void sign(Bytes& bytes, const Key& key) {
  REQUIRE(bytes.size() >= kTagSize);
  const std::size_t n = bytes.size() - kTagSize;
  crypto_auth_hmacsha512256(bytes.data() + n, bytes.data(), n, key.bytes.data());
}

// The content (everything but the tag) with `edit` applied, then signed.
template <typename Edit>
Bytes resigned(Bytes bytes, const Key& key, Edit edit) {
  Bytes content(bytes.begin(), bytes.end() - static_cast<std::ptrdiff_t>(kTagSize));
  edit(content);
  content.resize(content.size() + kTagSize);
  sign(content, key);
  return content;
}

CanFrame frame(std::uint32_t id, std::initializer_list<std::uint8_t> data) {
  CanFrame f;
  f.id = id;
  f.dlc = static_cast<std::uint8_t>(data.size());
  std::copy(data.begin(), data.end(), f.data.begin());
  return f;
}

Datagram data_datagram(std::initializer_list<CanFrame> frames) {
  Datagram d;
  d.sender = 1;
  d.sequence = 1000;
  d.timestamp_us = 123456789;
  d.epoch = 0xE90C;
  d.peer_epoch = 0x9EE7;
  for (const auto& f : frames) d.frames[d.frame_count++] = f;
  return d;
}

Datagram random_datagram(lever::Rng& rng, std::size_t count) {
  Datagram d;
  d.sender = static_cast<std::uint8_t>(rng.next());
  d.sequence = rng.next();
  d.timestamp_us = rng.next();
  d.epoch = rng.next();
  d.peer_epoch = rng.next();
  d.frame_count = count;
  for (std::size_t i = 0; i < count; ++i) {
    auto& f = d.frames[i];
    f.id = static_cast<std::uint32_t>(rng.next() % 0x800);
    f.dlc = static_cast<std::uint8_t>(rng.next() % 9);
    for (std::size_t b = 0; b < f.dlc; ++b) f.data[b] = static_cast<std::uint8_t>(rng.next());
  }
  return d;
}

Datagram the_largest() {
  Datagram d = data_datagram({});
  d.frame_count = kMaxFrames;
  for (std::size_t i = 0; i < kMaxFrames; ++i) {
    d.frames[i] = frame(static_cast<std::uint32_t>(0x100 + i), {1, 2, 3, 4, 5, 6, 7, static_cast<std::uint8_t>(i)});
  }
  return d;
}

void check_same(const Datagram& a, const Datagram& b) {
  CHECK(a.kind == b.kind);
  CHECK(a.sender == b.sender);
  CHECK(a.sequence == b.sequence);
  CHECK(a.timestamp_us == b.timestamp_us);
  CHECK(a.epoch == b.epoch);
  CHECK(a.peer_epoch == b.peer_epoch);
  CHECK(a.echo == b.echo);
  REQUIRE(a.frame_count == b.frame_count);
  for (std::size_t i = 0; i < a.frame_count; ++i) {
    CHECK(a.frames[i].id == b.frames[i].id);
    REQUIRE(a.frames[i].dlc == b.frames[i].dlc);
    for (std::size_t k = 0; k < a.frames[i].dlc; ++k) CHECK(a.frames[i].data[k] == b.frames[i].data[k]);
  }
}

}  // namespace

TEST_CASE("error codes keep their numbers and names", "[bridge][datagram]") {
  STATIC_REQUIRE(static_cast<int>(WireError::none) == 0);
  STATIC_REQUIRE(static_cast<int>(WireError::truncated) == 1);
  STATIC_REQUIRE(static_cast<int>(WireError::oversized) == 2);
  STATIC_REQUIRE(static_cast<int>(WireError::bad_magic) == 3);
  STATIC_REQUIRE(static_cast<int>(WireError::bad_version) == 4);
  STATIC_REQUIRE(static_cast<int>(WireError::bad_tag) == 5);
  STATIC_REQUIRE(static_cast<int>(WireError::bad_flags) == 6);
  STATIC_REQUIRE(static_cast<int>(WireError::bad_frame_count) == 7);
  STATIC_REQUIRE(static_cast<int>(WireError::bad_id) == 8);
  STATIC_REQUIRE(static_cast<int>(WireError::bad_dlc) == 9);
  STATIC_REQUIRE(static_cast<int>(WireError::trailing_bytes) == 10);
  STATIC_REQUIRE(static_cast<int>(WireError::bad_probe) == 11);
  STATIC_REQUIRE(static_cast<int>(WireError::buffer_too_small) == 12);
  CHECK(std::string(to_string(WireError::bad_tag)) == "bad_tag");
  CHECK(std::string(to_string(WireError::trailing_bytes)) == "trailing_bytes");
  CHECK(std::string(to_string(static_cast<WireError>(200))) == "unknown");
}

TEST_CASE("sizes are the spec's", "[bridge][datagram]") {
  STATIC_REQUIRE(kHeaderSize == 38);
  STATIC_REQUIRE(kMinDatagramSize == 70);
  STATIC_REQUIRE(kProbeDatagramSize == 94);
  STATIC_REQUIRE(kMaxDatagramSize == 422);
  CHECK(encode_bytes(the_largest(), test_key()).size() == kMaxDatagramSize);
  CHECK(encode_bytes(data_datagram({}), test_key()).size() == kMinDatagramSize);
}

TEST_CASE("the layout is the spec's, byte for byte", "[bridge][datagram]") {
  // The worked example of docs/datagram-format.md.
  Datagram d;
  d.sender = 1;
  d.sequence = 0x0102030405060708;
  d.timestamp_us = 0x00000000DEADBEEF;
  d.epoch = 0x1122334455667788;
  d.peer_epoch = 0x99AABBCCDDEEFF00;
  d.frame_count = 2;
  d.frames[0] = frame(0x101, {0x11, 0x22, 0x33, 0x44, 0x55, 0x66, 0x77, 0x88});
  d.frames[1] = frame(0x703, {0x02});
  d.frames[1].data[5] = 0xEE;  // beyond the dlc: not sent
  const Key key = test_key();
  const Bytes bytes = encode_bytes(d, key);
  const Bytes expected_content = {
      0x4C, 0x42, 0x02, 0x00, 0x01, 0x02,                                // magic "LB", version 2, flags, sender, count
      0x01, 0x02, 0x03, 0x04, 0x05, 0x06, 0x07, 0x08,                    // sequence
      0x00, 0x00, 0x00, 0x00, 0xDE, 0xAD, 0xBE, 0xEF,                    // timestamp, us
      0x11, 0x22, 0x33, 0x44, 0x55, 0x66, 0x77, 0x88,                    // epoch
      0x99, 0xAA, 0xBB, 0xCC, 0xDD, 0xEE, 0xFF, 0x00,                    // peer epoch
      0x01, 0x01, 0x08, 0x11, 0x22, 0x33, 0x44, 0x55, 0x66, 0x77, 0x88,  // id 0x101, dlc 8, data
      0x07, 0x03, 0x01, 0x02,                                            // id 0x703, dlc 1, data
  };
  REQUIRE(bytes.size() == expected_content.size() + kTagSize);
  CHECK(Bytes(bytes.begin(), bytes.end() - kTagSize) == expected_content);
  std::array<std::uint8_t, kTagSize> tag{};
  crypto_auth_hmacsha512256(tag.data(), expected_content.data(), expected_content.size(), key.bytes.data());
  CHECK(std::equal(tag.begin(), tag.end(), bytes.end() - kTagSize));
  // A known answer, computed independently (Python: hmac.new(key, content, hashlib.sha512).digest()[:32]).
  const Bytes known_tag = {0xda, 0x9b, 0x33, 0x4a, 0x26, 0x3d, 0xb4, 0xca, 0x13, 0x96, 0x0d,
                           0x43, 0x60, 0x06, 0x45, 0x9e, 0x3c, 0xe3, 0x80, 0x72, 0xc3, 0x53,
                           0x58, 0xe3, 0xd5, 0x33, 0xb9, 0x33, 0xdd, 0xd3, 0xbe, 0xe4};
  CHECK(Bytes(bytes.end() - kTagSize, bytes.end()) == known_tag);

  Datagram decoded;
  REQUIRE(decode_bytes(bytes, key, decoded) == WireError::none);
  CHECK(decoded.frames[1].data[5] == 0);  // zero beyond the dlc
}

TEST_CASE("probes: layout, round trip and the clock arithmetic", "[bridge][datagram][probe]") {
  const Key key = test_key();
  Datagram request;
  request.kind = Kind::probe_request;
  request.sender = 0;
  request.sequence = 77;
  request.timestamp_us = 1'000'000;  // t1
  const Bytes request_bytes = encode_bytes(request, key);
  REQUIRE(request_bytes.size() == kProbeDatagramSize);
  CHECK(request_bytes[3] == kFlagProbe);
  CHECK(request_bytes[5] == 0);
  CHECK(std::all_of(request_bytes.begin() + kHeaderSize, request_bytes.begin() + kHeaderSize + kProbeBodySize,
                    [](std::uint8_t b) { return b == 0; }));

  Datagram received;
  REQUIRE(decode_bytes(request_bytes, key, received) == WireError::none);
  check_same(received, request);

  // The replier's clock is 5000 us ahead; 300 us each way; it takes 40 us to answer.
  const auto reply = make_probe_reply(received, 1, 9, 1'000'000 + 5000 + 300, 1'000'000 + 5000 + 340);
  const Bytes reply_bytes = encode_bytes(reply, key);
  REQUIRE(reply_bytes.size() == kProbeDatagramSize);
  CHECK(reply_bytes[3] == (kFlagProbe | kFlagReply));
  CHECK(reply_bytes[kHeaderSize + 7] == 77);  // echo sequence, big-endian
  Datagram back;
  REQUIRE(decode_bytes(reply_bytes, key, back) == WireError::none);
  check_same(back, reply);
  CHECK(back.echo.sequence == 77);
  CHECK(back.echo.request_timestamp_us == 1'000'000);

  const auto timing = probe_timing(back, 1'000'000 + 640);  // t4 on the requester's clock
  CHECK(timing.round_trip_us == 600);
  CHECK(timing.offset_us == 5000);

  SECTION("a replier behind, across the clocks' wrap") {
    Datagram late = back;
    late.echo.request_timestamp_us = 10;                      // t1
    late.echo.receive_timestamp_us = 10 + 300 - 7000;         // t2: wraps below zero
    late.timestamp_us = late.echo.receive_timestamp_us + 40;  // t3
    const auto t = probe_timing(late, 10 + 640);
    CHECK(t.round_trip_us == 600);
    CHECK(t.offset_us == -7000);
  }
}

TEST_CASE("round trip of 0 to 32 frames of random content", "[bridge][datagram]") {
  lever::Rng rng(20240611);
  const Key key = generate_key();
  for (std::size_t count = 0; count <= kMaxFrames; ++count) {
    for (int repeat = 0; repeat < 20; ++repeat) {
      Datagram d = random_datagram(rng, count);
      if (repeat == 0) {
        d.sequence = 0;
        d.timestamp_us = 0;
      } else if (repeat == 1) {
        d.sequence = std::numeric_limits<std::uint64_t>::max();
        d.timestamp_us = std::numeric_limits<std::uint64_t>::max();
      }
      CAPTURE(count, repeat);
      const Bytes bytes = encode_bytes(d, key);
      CHECK(bytes.size() == encoded_size(d));
      Datagram decoded;
      REQUIRE(decode_bytes(bytes, key, decoded) == WireError::none);
      check_same(decoded, d);
      CHECK(encode_bytes(decoded, key) == bytes);
    }
  }
}

TEST_CASE("too short or too long is refused before the tag", "[bridge][datagram][errors]") {
  const Key key = test_key();
  for (const auto& d : {the_largest(), data_datagram({frame(0x100, {1, 2})})}) {
    const Bytes bytes = encode_bytes(d, key);
    // Every prefix: too short to be a datagram, or its tag no longer matches.
    for (std::size_t n = 0; n < bytes.size(); ++n) {
      CAPTURE(n);
      const Bytes cut(bytes.begin(), bytes.begin() + static_cast<std::ptrdiff_t>(n));
      CHECK(decode_bytes(cut, key) == (n < kMinDatagramSize ? WireError::truncated : WireError::bad_tag));
    }
  }
  Bytes big = encode_bytes(the_largest(), key);
  big.push_back(0);
  CHECK(decode_bytes(big, key) == WireError::oversized);
  sign(big, key);
  CHECK(decode_bytes(big, key) == WireError::oversized);  // even when authentic
  big.resize(9000, 0xAA);
  CHECK(decode_bytes(big, key) == WireError::oversized);
}

TEST_CASE("an authentic datagram whose content runs past its end is truncated", "[bridge][datagram][errors]") {
  const Key key = test_key();
  for (const auto& d : {the_largest(), data_datagram({frame(0x100, {1, 2}), frame(0x7FF, {})})}) {
    const Bytes bytes = encode_bytes(d, key);
    const std::size_t content = bytes.size() - kTagSize;
    for (std::size_t n = kHeaderSize; n < content; ++n) {
      CAPTURE(n);
      const Bytes cut = resigned(bytes, key, [n](Bytes& c) { c.resize(n); });
      CHECK(decode_bytes(cut, key) == WireError::truncated);
    }
  }
  Datagram probe;
  probe.kind = Kind::probe_request;
  const Bytes bytes = encode_bytes(probe, key);
  for (std::size_t n = kHeaderSize; n < kHeaderSize + kProbeBodySize; ++n) {
    CAPTURE(n);
    CHECK(decode_bytes(resigned(bytes, key, [n](Bytes& c) { c.resize(n); }), key) == WireError::truncated);
  }
}

TEST_CASE("bytes left over between content and tag are refused", "[bridge][datagram][errors]") {
  const Key key = test_key();
  const auto add = [](std::size_t n) { return [n](Bytes& c) { c.insert(c.end(), n, 0); }; };
  const Bytes data = encode_bytes(data_datagram({frame(0x100, {1, 2})}), key);
  CHECK(decode_bytes(resigned(data, key, add(1)), key) == WireError::trailing_bytes);
  CHECK(decode_bytes(resigned(data, key, add(11)), key) == WireError::trailing_bytes);
  Datagram probe;
  probe.kind = Kind::probe_reply;
  const Bytes probe_bytes = encode_bytes(probe, key);
  CHECK(decode_bytes(resigned(probe_bytes, key, add(1)), key) == WireError::trailing_bytes);
  // A keep-alive with a stray byte: still a datagram of legal size.
  const Bytes empty = encode_bytes(data_datagram({}), key);
  CHECK(decode_bytes(resigned(empty, key, add(3)), key) == WireError::trailing_bytes);
}

TEST_CASE("another magic or version is named before the tag", "[bridge][datagram][errors]") {
  const Key key = test_key();
  const Bytes bytes = encode_bytes(data_datagram({frame(0x100, {1})}), key);
  for (const std::size_t at : {0, 1}) {
    Bytes wrong = bytes;
    wrong[at] ^= 0x20;
    CHECK(decode_bytes(wrong, key) == WireError::bad_magic);
    CHECK(decode_bytes(resigned(bytes, key, [at](Bytes& c) { c[at] ^= 0x20; }), key) == WireError::bad_magic);
  }
  for (const std::uint8_t version : {std::uint8_t{0}, std::uint8_t{1}, std::uint8_t{3}, std::uint8_t{255}}) {
    CHECK(decode_bytes(resigned(bytes, key, [version](Bytes& c) { c[2] = version; }), key) == WireError::bad_version);
    Bytes short_one = {0x4C, 0x42, version};  // a version mismatch is told even for a short datagram
    CHECK(decode_bytes(short_one, key) == WireError::bad_version);
  }
  CHECK(decode_bytes(Bytes{0x4C, 0x42}, key) == WireError::truncated);
  CHECK(decode_bytes(Bytes{}, key) == WireError::truncated);
}

TEST_CASE("each field out of range, in an authentic datagram", "[bridge][datagram][errors]") {
  const Key key = test_key();
  const Bytes data = encode_bytes(data_datagram({frame(0x100, {1, 2}), frame(0x110, {3})}), key);
  const auto decode_edited = [&](const Bytes& base, auto edit) { return decode_bytes(resigned(base, key, edit), key); };

  SECTION("flags: each reserved bit, and reply without probe") {
    for (int bit = 2; bit < 8; ++bit) {
      CAPTURE(bit);
      CHECK(decode_edited(data, [bit](Bytes& c) { c[3] = static_cast<std::uint8_t>(1 << bit); }) ==
            WireError::bad_flags);
    }
    CHECK(decode_edited(data, [](Bytes& c) { c[3] = kFlagReply; }) == WireError::bad_flags);
  }
  SECTION("frame count above 32") {
    for (const int count : {33, 34, 100, 255}) {
      CHECK(decode_edited(data, [count](Bytes& c) { c[5] = static_cast<std::uint8_t>(count); }) ==
            WireError::bad_frame_count);
    }
  }
  SECTION("frame count disagreeing with the frames") {
    CHECK(decode_edited(data, [](Bytes& c) { c[5] = 3; }) == WireError::truncated);
    CHECK(decode_edited(data, [](Bytes& c) { c[5] = 1; }) == WireError::trailing_bytes);
  }
  SECTION("id above 0x7FF: the field's reserved upper bits") {
    for (const unsigned id : {0x800u, 0x0FFFu, 0x8100u, 0xFFFFu}) {
      CAPTURE(id);
      CHECK(decode_edited(data, [id](Bytes& c) {
              c[kHeaderSize] = static_cast<std::uint8_t>(id >> 8);
              c[kHeaderSize + 1] = static_cast<std::uint8_t>(id);
            }) == WireError::bad_id);
    }
    CHECK(decode_edited(data, [](Bytes& c) { c[kHeaderSize + 5] = 0x08; }) == WireError::bad_id);  // the second frame
  }
  SECTION("dlc above 8") {
    for (const int dlc : {9, 15, 64, 255}) {
      CHECK(decode_edited(data, [dlc](Bytes& c) { c[kHeaderSize + 2] = static_cast<std::uint8_t>(dlc); }) ==
            WireError::bad_dlc);
    }
  }
  SECTION("probes") {
    Datagram request;
    request.kind = Kind::probe_request;
    const Bytes probe = encode_bytes(request, key);
    for (std::size_t at = kHeaderSize; at < kHeaderSize + kProbeBodySize; ++at) {
      CHECK(decode_edited(probe, [at](Bytes& c) { c[at] = 1; }) == WireError::bad_probe);
    }
    CHECK(decode_edited(probe, [](Bytes& c) { c[5] = 1; }) == WireError::bad_frame_count);
    // A data datagram cannot pass for a probe, nor the reverse: the sizes and fields disagree.
    CHECK(decode_edited(probe, [](Bytes& c) { c[3] = 0; }) == WireError::trailing_bytes);
  }
}

TEST_CASE("any flipped bit fails, and before the tag only magic and version are read", "[bridge][datagram][errors]") {
  const Key key = test_key();
  Datagram probe;
  probe.kind = Kind::probe_request;
  for (const auto& d : {the_largest(), data_datagram({frame(0x080, {5})}), probe}) {
    const Bytes bytes = encode_bytes(d, key);
    for (std::size_t bit = 0; bit < bytes.size() * 8; ++bit) {
      Bytes flipped = bytes;
      flipped[bit / 8] ^= static_cast<std::uint8_t>(1u << (bit % 8));
      const auto expected = bit < 16 ? WireError::bad_magic : bit < 24 ? WireError::bad_version : WireError::bad_tag;
      CAPTURE(bit);
      CHECK(decode_bytes(flipped, key) == expected);
    }
  }
}

TEST_CASE("another key fails", "[bridge][datagram][errors]") {
  const Key key = test_key();
  const Bytes bytes = encode_bytes(the_largest(), key);
  CHECK(decode_bytes(bytes, test_key(2)) == WireError::bad_tag);
  CHECK(decode_bytes(bytes, generate_key()) == WireError::bad_tag);
  for (std::size_t bit = 0; bit < kKeySize * 8; bit += 13) {
    Key near = key;
    near.bytes[bit / 8] ^= static_cast<std::uint8_t>(1u << (bit % 8));
    CHECK(decode_bytes(bytes, near) == WireError::bad_tag);
  }
}

TEST_CASE("a failed decode leaves an empty datagram", "[bridge][datagram][errors]") {
  const Key key = test_key();
  const Bytes bytes = encode_bytes(data_datagram({frame(0x100, {1, 2}), frame(0x110, {3})}), key);
  Datagram out;
  REQUIRE(decode_bytes(bytes, key, out) == WireError::none);
  CHECK(out.frame_count == 2);
  // Fails after the first frame was parsed.
  const Bytes bad = resigned(bytes, key, [](Bytes& c) { c[kHeaderSize + 5 + 2] = 9; });
  REQUIRE(decode_bytes(bad, key, out) == WireError::bad_dlc);
  CHECK(out.frame_count == 0);
  CHECK(out.sequence == 0);
  CHECK(out.epoch == 0);
  CHECK(out.peer_epoch == 0);
  CHECK(out.frames[0].id == 0);
  REQUIRE(decode_bytes(bytes, key, out) == WireError::none);
  REQUIRE(decode_bytes(bytes, test_key(9), out) == WireError::bad_tag);
  CHECK(out.sequence == 0);
}

TEST_CASE("encode refuses what the format cannot carry and writes nothing", "[bridge][datagram][errors]") {
  const Key key = test_key();
  std::array<std::uint8_t, kMaxDatagramSize> buffer{};
  buffer.fill(0x5A);
  const auto untouched = [&] { return std::all_of(buffer.begin(), buffer.end(), [](auto b) { return b == 0x5A; }); };
  const auto refused = [&](const Datagram& d, std::span<std::uint8_t> out) {
    const auto result = encode(d, key, out);
    CHECK_FALSE(result);
    CHECK(result.size == 0);
    CHECK(untouched());
    return result.error;
  };

  Datagram d = the_largest();
  d.frame_count = kMaxFrames + 1;
  CHECK(refused(d, buffer) == WireError::bad_frame_count);
  d = data_datagram({frame(0x800, {1})});
  CHECK(refused(d, buffer) == WireError::bad_id);
  d = data_datagram({frame(0x100, {1})});
  d.frames[0].dlc = 9;
  CHECK(refused(d, buffer) == WireError::bad_dlc);
  d = data_datagram({frame(0x100, {1})});
  d.kind = static_cast<Kind>(3);
  CHECK(refused(d, buffer) == WireError::bad_flags);
  d = data_datagram({frame(0x100, {1})});
  d.kind = Kind::probe_reply;
  CHECK(refused(d, buffer) == WireError::bad_frame_count);
  d = Datagram{};
  d.kind = Kind::probe_request;
  d.echo.sequence = 1;
  CHECK(refused(d, buffer) == WireError::bad_probe);

  const Datagram big = the_largest();
  CHECK(refused(big, std::span(buffer).first(kMaxDatagramSize - 1)) == WireError::buffer_too_small);
  CHECK(refused(big, {}) == WireError::buffer_too_small);
  const auto fits = encode(big, key, std::span(buffer).first(kMaxDatagramSize));
  CHECK(fits);
  CHECK(fits.size == kMaxDatagramSize);
}
