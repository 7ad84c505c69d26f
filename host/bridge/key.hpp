#pragma once
// The bridge's shared secret: 32 bytes, kept in a key file of 64 hex digits (docs/datagram-format.md, "Key file").
//
// Errors here are configuration errors met once at start-up, so they are exceptions (KeyError) whose message
// names the file and says what to do; the per-datagram code (datagram.hpp) never throws.
#include <sodium.h>

#include <array>
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <stdexcept>
#include <string>
#include <string_view>

namespace lever::bridge {

inline constexpr std::size_t kKeySize = 32;  // crypto_auth_hmacsha512256_KEYBYTES

// A 32-byte HMAC key. Wiped when destroyed, so copies do not linger in freed stack or heap memory.
struct Key {
  std::array<std::uint8_t, kKeySize> bytes{};

  Key() = default;
  explicit Key(const std::array<std::uint8_t, kKeySize>& b) noexcept : bytes(b) {}
  Key(const Key&) = default;
  Key& operator=(const Key&) = default;
  ~Key();
};

// The HMAC key as the relay uses it: HMAC-SHA-512/256's inner and outer padded states, hashed once here instead of
// on every datagram (a one-shot crypto_auth_hmacsha512256 hashes both 128-byte key blocks each time, about as much
// work again as a short datagram). A copy of the state per datagram is all encode/decode then pay. The tags are
// bit for bit those of the one-shot call: the wire format does not change. Wiped when destroyed.
class MacKey {
 public:
  explicit MacKey(const Key& key) noexcept;
  MacKey(const MacKey&) noexcept = default;
  MacKey& operator=(const MacKey&) noexcept = default;
  ~MacKey();

  // The state after the key: copy it, add the message, finalise.
  const crypto_auth_hmacsha512256_state& state() const noexcept { return state_; }

 private:
  crypto_auth_hmacsha512256_state state_{};
};

// A key file that cannot be used; what() names the file and the remedy.
class KeyError : public std::runtime_error {
 public:
  explicit KeyError(const std::string& what, int error_number = 0) : std::runtime_error(what), errno_(error_number) {}
  // The errno of the failed system call, 0 for a key that is there but wrong.
  int error_number() const noexcept { return errno_; }

 private:
  int errno_;
};

// Initialises libsodium (idempotent, thread-safe). encode/decode and the functions below call it themselves;
// a program may call it once at start-up to fail early. Returns false if libsodium cannot start (no RNG).
bool init_crypto() noexcept;

// 32 bytes from libsodium's CSPRNG. Throws KeyError if libsodium cannot be initialised.
Key generate_key();

// A bridge's epoch for one run (peer_session.hpp): 64 bits from libsodium's CSPRNG, never 0. Throws KeyError if
// libsodium cannot be initialised.
std::uint64_t generate_epoch();

// The key file's content: 64 lowercase hex digits and a newline.
std::string format_key(const Key& key);

// Parses a key file's content: exactly 64 hex digits (either case), optionally followed by one "\n".
// Anything else (other length, non-hex, CR, spaces, a second line) and the all-zero key are refused.
// `origin` names the source in error messages.
Key parse_key(std::string_view text, std::string_view origin = "key");

// Reads a key file. Refuses a file that is not a regular file, is larger than a key file can be, or whose mode
// grants any access to group or others (mode & 077; the message says to run chmod 600), then parses it.
// Permissions are checked on the opened file (fstat), not on the path, so the check and the read agree.
Key load_key_file(const std::filesystem::path& path);

// Writes format_key(key) to a new file created with mode 0600; refuses to overwrite an existing file.
void write_key_file(const std::filesystem::path& path, const Key& key);

}  // namespace lever::bridge
