// Writes the seed corpus of the datagram fuzzer (fuzz/corpus/datagram/): valid datagrams signed with the fuzz key,
// and malformed ones, most of them re-signed so that they are refused after the tag, where the parsing is.
// usage: make_datagram_corpus DIR     (fuzz/run-datagram-fuzzer --make-corpus runs it)
#include <sodium.h>

#include <array>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "datagram.hpp"
#include "fuzz_key.hpp"

namespace {

using namespace lever::bridge;
using Bytes = std::vector<std::uint8_t>;

const Key key = fuzz::fuzz_key();

Bytes encoded(const Datagram& d) {
  std::array<std::uint8_t, kMaxDatagramSize> buffer{};
  const auto result = encode(d, key, buffer);
  if (!result) {
    std::fprintf(stderr, "cannot encode a seed: %s\n", to_string(result.error));
    std::exit(1);
  }
  return Bytes(buffer.begin(), buffer.begin() + static_cast<std::ptrdiff_t>(result.size));
}

void resign(Bytes& bytes) {
  const std::size_t n = bytes.size() - kTagSize;
  crypto_auth_hmacsha512256(bytes.data() + n, bytes.data(), n, key.bytes.data());
}

Datagram with_frames(std::size_t count, std::uint8_t dlc) {
  Datagram d;
  d.sender = 1;
  d.sequence = 1'000'000 + count;
  d.timestamp_us = 86'400'000'000;
  d.epoch = 0x5EED'0000'0000'0001;
  d.peer_epoch = 0x5EED'0000'0000'0002;
  d.frame_count = count;
  for (std::size_t i = 0; i < count; ++i) {
    auto& f = d.frames[i];
    f.id = static_cast<std::uint32_t>(0x100 + (i % 32));
    f.dlc = dlc;
    for (std::size_t b = 0; b < dlc; ++b) f.data[b] = static_cast<std::uint8_t>(i * 8 + b);
  }
  return d;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: %s DIR\n", argv[0]);
    return 2;
  }
  const std::filesystem::path dir(argv[1]);
  std::filesystem::create_directories(dir);
  int written = 0;
  const auto write = [&](const std::string& name, const Bytes& bytes) {
    std::ofstream(dir / name, std::ios::binary)
        .write(reinterpret_cast<const char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
    ++written;
  };

  // Valid.
  write("valid-keepalive", encoded(with_frames(0, 0)));
  write("valid-1-frame", encoded(with_frames(1, 8)));
  write("valid-3-frames", encoded(with_frames(3, 8)));
  write("valid-32-frames-dlc-8", encoded(with_frames(32, 8)));
  write("valid-32-frames-dlc-0", encoded(with_frames(32, 0)));
  Datagram mixed = with_frames(9, 0);
  for (std::size_t i = 0; i < 9; ++i) {
    mixed.frames[i].dlc = static_cast<std::uint8_t>(i);
    mixed.frames[i].id = static_cast<std::uint32_t>(i == 8 ? 0x7FF : i * 0x0F1);
  }
  mixed.sequence = ~std::uint64_t{0};
  write("valid-dlc-0-to-8", encoded(mixed));
  Datagram request;
  request.kind = Kind::probe_request;
  request.sequence = 5;
  request.timestamp_us = 1'000'000;
  request.epoch = 0x5EED'0000'0000'0002;
  write("valid-probe-request", encoded(request));
  write("valid-probe-reply", encoded(make_probe_reply(request, 1, 17, 1'005'300, 1'005'340)));

  // Refused before the tag.
  const Bytes three = encoded(with_frames(3, 8));
  write("short-2-bytes", Bytes(three.begin(), three.begin() + 2));
  write("short-69-bytes", Bytes(three.begin(), three.begin() + kMinDatagramSize - 1));
  Bytes magic = three;
  magic[0] = 'X';
  write("bad-magic", magic);
  Bytes version = three;
  version[2] = 1;  // the version before the epochs
  write("bad-version", version);
  Bytes oversized = encoded(with_frames(32, 8));
  oversized.push_back(0);
  write("oversized", oversized);
  Bytes flipped = three;
  flipped[30] ^= 0x01;
  write("bad-tag", flipped);

  // Authentic but malformed: refused after the tag.
  const auto resigned = [&](Bytes bytes, auto edit) {
    Bytes content(bytes.begin(), bytes.end() - static_cast<std::ptrdiff_t>(kTagSize));
    edit(content);
    content.resize(content.size() + kTagSize);
    resign(content);
    return content;
  };
  write("signed-bad-flags", resigned(three, [](Bytes& c) { c[3] = 0x04; }));
  write("signed-reply-without-probe", resigned(three, [](Bytes& c) { c[3] = kFlagReply; }));
  write("signed-count-33", resigned(three, [](Bytes& c) { c[5] = 33; }));
  write("signed-count-too-high", resigned(three, [](Bytes& c) { c[5] = 4; }));
  write("signed-count-too-low", resigned(three, [](Bytes& c) { c[5] = 2; }));
  write("signed-bad-id", resigned(three, [](Bytes& c) { c[kHeaderSize] = 0x08; }));
  write("signed-bad-dlc", resigned(three, [](Bytes& c) { c[kHeaderSize + 2] = 9; }));
  write("signed-trailing-byte", resigned(three, [](Bytes& c) { c.push_back(0); }));
  write("signed-cut-frame", resigned(three, [](Bytes& c) { c.resize(c.size() - 3); }));
  const Bytes probe = encoded(request);
  write("signed-probe-with-frames", resigned(probe, [](Bytes& c) { c[5] = 1; }));
  write("signed-probe-request-with-echo", resigned(probe, [](Bytes& c) { c[kHeaderSize + 7] = 1; }));
  write("signed-probe-short-body", resigned(probe, [](Bytes& c) { c.resize(c.size() - 8); }));
  std::printf("wrote %d seeds to %s\n", written, dir.c_str());
  return 0;
}
