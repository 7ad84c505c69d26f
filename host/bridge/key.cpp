// Key generation, formatting and the key file (docs/datagram-format.md, "Key file").
#include "key.hpp"

#include <fcntl.h>
#include <fmt/format.h>
#include <sodium.h>
#include <sys/stat.h>
#include <unistd.h>

#include <array>
#include <cerrno>
#include <system_error>

#include "shown_value.hpp"

namespace lever::bridge {

static_assert(kKeySize == crypto_auth_hmacsha512256_KEYBYTES);

namespace {

constexpr std::size_t kHexDigits = 2 * kKeySize;
// A key file is 64 or 65 bytes. Files up to 255 bytes are parsed, so that a CRLF ending, a stray space or a second
// line get their own message; a file that fills the buffer is simply too long.
constexpr std::size_t kReadLimit = 256;

int hex_value(char c) noexcept {
  if (c >= '0' && c <= '9') return c - '0';
  if (c >= 'a' && c <= 'f') return c - 'a' + 10;
  if (c >= 'A' && c <= 'F') return c - 'A' + 10;
  return -1;
}

// Closes a file descriptor on every path out.
class FileDescriptor {
 public:
  explicit FileDescriptor(int fd) noexcept : fd_(fd) {}
  FileDescriptor(const FileDescriptor&) = delete;
  FileDescriptor& operator=(const FileDescriptor&) = delete;
  ~FileDescriptor() {
    if (fd_ >= 0) ::close(fd_);
  }
  int get() const noexcept { return fd_; }
  // Closes now and reports the error (close can report a failed write).
  int close() noexcept {
    const int result = ::close(fd_);
    fd_ = -1;
    return result;
  }

 private:
  int fd_;
};

// A fixed buffer that is wiped when it goes out of scope: it holds key material.
template <std::size_t N>
struct WipedBuffer {
  std::array<char, N> data{};
  WipedBuffer() = default;
  WipedBuffer(const WipedBuffer&) = delete;
  WipedBuffer& operator=(const WipedBuffer&) = delete;
  ~WipedBuffer() { sodium_memzero(data.data(), data.size()); }
};

std::string errno_text(int error) { return std::generic_category().message(error); }

}  // namespace

Key::~Key() { sodium_memzero(bytes.data(), bytes.size()); }

MacKey::MacKey(const Key& key) noexcept {
  // init needs no randomness, so a libsodium that cannot start its RNG still computes the state.
  [[maybe_unused]] const bool ready = init_crypto();
  crypto_auth_hmacsha512256_init(&state_, key.bytes.data(), key.bytes.size());
}

MacKey::~MacKey() { sodium_memzero(&state_, sizeof state_); }

bool init_crypto() noexcept { return sodium_init() >= 0; }

Key generate_key() {
  if (!init_crypto()) throw KeyError("cannot initialise libsodium (no random number generator?)");
  Key key;
  randombytes_buf(key.bytes.data(), key.bytes.size());
  return key;
}

std::uint64_t generate_epoch() {
  if (!init_crypto()) throw KeyError("cannot initialise libsodium (no random number generator?)");
  std::uint64_t epoch = 0;
  while (epoch == 0) randombytes_buf(&epoch, sizeof epoch);
  return epoch;
}

std::string format_key(const Key& key) {
  static constexpr char kDigits[] = "0123456789abcdef";
  std::string text;
  text.reserve(kHexDigits + 1);
  for (const std::uint8_t byte : key.bytes) {
    text.push_back(kDigits[byte >> 4]);
    text.push_back(kDigits[byte & 0x0F]);
  }
  text.push_back('\n');
  return text;
}

Key parse_key(std::string_view text, std::string_view origin) {
  // One optional final newline; nothing else besides the digits.
  std::string_view digits = text;
  if (!digits.empty() && digits.back() == '\n') digits.remove_suffix(1);
  if (!digits.empty() && digits.back() == '\r') {
    throw KeyError(
        fmt::format("{}: ends in a carriage return (CRLF line ending); a key file is 64 hex digits and "
                    "a newline (\\n)",
                    origin));
  }
  if (digits.size() != kHexDigits) {
    throw KeyError(fmt::format("{}: must hold exactly {} hex digits and a newline, found {} characters{}", origin,
                               kHexDigits, digits.size(),
                               digits.find('\n') != std::string_view::npos ? " on more than one line" : ""));
  }
  Key key;
  std::uint8_t any = 0;
  for (std::size_t i = 0; i < kKeySize; ++i) {
    const int high = hex_value(digits[2 * i]);
    const int low = hex_value(digits[2 * i + 1]);
    if (high < 0 || low < 0) {
      const std::size_t at = high < 0 ? 2 * i : 2 * i + 1;
      // Name the position, not the character: this is a secret.
      throw KeyError(fmt::format("{}: character {} is not a hex digit (0-9, a-f, A-F)", origin, at + 1));
    }
    key.bytes[i] = static_cast<std::uint8_t>(high << 4 | low);
    any = static_cast<std::uint8_t>(any | key.bytes[i]);
  }
  if (any == 0) {
    throw KeyError(
        fmt::format("{}: the key is all zeros, a placeholder rather than a secret; generate one with "
                    "`lever-bridge keygen`",
                    origin));
  }
  return key;
}

Key load_key_file(const std::filesystem::path& path) {
  const std::string name = shown_value(path.string(), 200);
  FileDescriptor fd(::open(path.c_str(), O_RDONLY | O_CLOEXEC | O_NOCTTY | O_NONBLOCK));
  if (fd.get() < 0) {
    const int error = errno;
    throw KeyError(fmt::format("key file {}: cannot open: {}", name, errno_text(error)), error);
  }
  struct stat info {};
  if (::fstat(fd.get(), &info) != 0) {
    const int error = errno;
    throw KeyError(fmt::format("key file {}: cannot stat: {}", name, errno_text(error)));
  }
  if (!S_ISREG(info.st_mode)) throw KeyError(fmt::format("key file {}: not a regular file", name));
  const auto mode = static_cast<unsigned>(info.st_mode & 07777);
  if ((mode & 077) != 0) {
    throw KeyError(
        fmt::format("key file {}: is accessible by group or others (mode {:04o}); the key is a secret: "
                    "run `chmod 600 {}`",
                    name, mode, name));
  }

  WipedBuffer<kReadLimit> buffer;
  std::size_t length = 0;
  while (length < buffer.data.size()) {
    const ssize_t got = ::read(fd.get(), buffer.data.data() + length, buffer.data.size() - length);
    if (got < 0) {
      if (errno == EINTR) continue;
      const int error = errno;
      throw KeyError(fmt::format("key file {}: cannot read: {}", name, errno_text(error)));
    }
    if (got == 0) break;
    length += static_cast<std::size_t>(got);
  }
  if (length == buffer.data.size()) {
    throw KeyError(
        fmt::format("key file {}: too long; a key file is exactly {} hex digits and a newline", name, kHexDigits));
  }
  return parse_key(std::string_view(buffer.data.data(), length), fmt::format("key file {}", name));
}

void write_key_file(const std::filesystem::path& path, const Key& key) {
  const std::string name = shown_value(path.string(), 200);
  FileDescriptor fd(::open(path.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC | O_NOFOLLOW, 0600));
  if (fd.get() < 0) {
    const int error = errno;
    throw KeyError(fmt::format("key file {}: cannot create{}: {}", name,
                               error == EEXIST ? " (it exists; a key is never overwritten)" : "", errno_text(error)),
                   error);
  }
  // The umask can only remove bits, but make the mode exact anyway.
  if (::fchmod(fd.get(), 0600) != 0) {
    const int error = errno;
    throw KeyError(fmt::format("key file {}: cannot chmod 600: {}", name, errno_text(error)));
  }
  std::string text = format_key(key);
  std::size_t written = 0;
  int error = 0;
  while (written < text.size()) {
    const ssize_t put = ::write(fd.get(), text.data() + written, text.size() - written);
    if (put < 0) {
      if (errno == EINTR) continue;
      error = errno;
      break;
    }
    written += static_cast<std::size_t>(put);
  }
  sodium_memzero(text.data(), text.size());
  if (error == 0 && ::fsync(fd.get()) != 0) error = errno;
  if (fd.close() != 0 && error == 0) error = errno;
  if (error != 0) {
    ::unlink(path.c_str());
    throw KeyError(fmt::format("key file {}: cannot write: {}", name, errno_text(error)), error);
  }
}

}  // namespace lever::bridge
