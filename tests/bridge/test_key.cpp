// Keys and the key file: 64 hex digits and a newline, mode 0600, refused otherwise with a message saying why.
#include <sys/stat.h>
#include <unistd.h>

#include <catch2/catch.hpp>
#include <filesystem>
#include <fstream>
#include <string>

#include "key.hpp"

namespace fs = std::filesystem;
using namespace lever::bridge;

namespace {

const std::string kHex = "000102030405060708090a0b0c0d0e0f101112131415161718191a1b1c1d1e1f";

class TempDir {
 public:
  TempDir() {
    std::string pattern = (fs::temp_directory_path() / "lever-key-test-XXXXXX").string();
    path_ = ::mkdtemp(pattern.data());
  }
  ~TempDir() { fs::remove_all(path_); }
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;
  fs::path write(const std::string& name, const std::string& content, mode_t mode = 0600) const {
    const auto file = path_ / name;
    std::ofstream(file, std::ios::binary) << content;
    ::chmod(file.c_str(), mode);
    return file;
  }
  const fs::path& path() const { return path_; }

 private:
  fs::path path_;
};

// The message parse_key or load_key_file gives, or "" if it accepted.
template <typename F>
std::string refusal(F&& f) {
  try {
    f();
  } catch (const KeyError& e) {
    return e.what();
  }
  return "";
}

// kHex with one character replaced (also sidesteps a GCC 12 -Wrestrict false positive on "x" + string).
std::string hex_with(std::size_t at, char c) {
  std::string text = kHex;
  text[at] = c;
  return text;
}

std::string parse_refusal(const std::string& text) {
  return refusal([&] { parse_key(text, "test"); });
}

}  // namespace

TEST_CASE("format_key writes 64 lowercase hex digits and a newline, parse_key reads them back", "[bridge][key]") {
  const Key key = parse_key(kHex + "\n");
  for (std::size_t i = 0; i < kKeySize; ++i) CHECK(key.bytes[i] == i);
  CHECK(format_key(key) == kHex + "\n");

  const Key random = generate_key();
  const std::string text = format_key(random);
  REQUIRE(text.size() == 65);
  CHECK(text.find_first_not_of("0123456789abcdef") == 64);
  CHECK(parse_key(text).bytes == random.bytes);
}

TEST_CASE("generate_key gives a different key each time", "[bridge][key]") {
  CHECK(init_crypto());
  const Key a = generate_key();
  const Key b = generate_key();
  CHECK(a.bytes != b.bytes);
  CHECK(a.bytes != Key{}.bytes);
}

TEST_CASE("parse_key: what is accepted", "[bridge][key]") {
  CHECK(parse_key(kHex + "\n").bytes[31] == 0x1f);
  // Missing final newline: accepted, as `printf %s` or an editor without final newline writes it.
  CHECK(parse_key(kHex).bytes[31] == 0x1f);
  std::string upper = kHex;
  for (auto& c : upper) c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
  CHECK(parse_key(upper + "\n").bytes[10] == 0x0a);
}

TEST_CASE("parse_key: what is refused, and why", "[bridge][key]") {
  using Catch::Matchers::Contains;
  CHECK_THAT(parse_refusal(""), Contains("exactly 64 hex digits") && Contains("found 0"));
  CHECK_THAT(parse_refusal("\n"), Contains("found 0"));
  CHECK_THAT(parse_refusal(kHex.substr(0, 63) + "\n"), Contains("found 63"));
  CHECK_THAT(parse_refusal(kHex + "0\n"), Contains("found 65"));
  CHECK_THAT(parse_refusal(kHex + "\n\n"), Contains("more than one line"));
  CHECK_THAT(parse_refusal(kHex + "\n" + kHex + "\n"), Contains("more than one line"));
  CHECK_THAT(parse_refusal(hex_with(0, ' ') + "\n"), Contains("character 1 is not a hex digit"));
  CHECK_THAT(parse_refusal(hex_with(40, 'g') + "\n"), Contains("character 41"));
  CHECK_THAT(parse_refusal(kHex.substr(0, 63) + " \n"), Contains("character 64"));
  CHECK_THAT(parse_refusal(kHex + "\r\n"), Contains("carriage return"));
  CHECK_THAT(parse_refusal(kHex + " \n"), Contains("found 65"));
  CHECK_THAT(parse_refusal(hex_with(1, 'x') + "\n"), Contains("character 2"));
  CHECK_THAT(parse_refusal(std::string(64, '0') + "\n"), Contains("all zeros") && Contains("keygen"));
  CHECK_THAT(parse_refusal(""), Contains("test:"));  // names its origin
}

TEST_CASE("load_key_file: mode 0600 and 0400 are accepted", "[bridge][key]") {
  TempDir dir;
  CHECK(load_key_file(dir.write("key", kHex + "\n", 0600)).bytes[1] == 1);
  CHECK(load_key_file(dir.write("key-ro", kHex + "\n", 0400)).bytes[1] == 1);
  CHECK(load_key_file(dir.write("key-x", kHex + "\n", 0700)).bytes[1] == 1);
  CHECK(load_key_file(dir.write("key-no-newline", kHex, 0600)).bytes[1] == 1);
}

TEST_CASE("load_key_file: any access for group or others is refused, with the fix", "[bridge][key]") {
  using Catch::Matchers::Contains;
  TempDir dir;
  for (const mode_t mode : {0644, 0640, 0604, 0660, 0610, 0601, 0666, 0602}) {
    CAPTURE(mode);
    const auto file = dir.write("key", kHex + "\n", mode);
    const auto message = refusal([&] { load_key_file(file); });
    CHECK_THAT(message, Contains(file.string()) && Contains("group or others") && Contains("chmod 600"));
    REQUIRE(::chmod(file.c_str(), 0600) == 0);
    CHECK(load_key_file(file).bytes[2] == 2);
    fs::remove(file);
  }
  const auto file = dir.write("key", kHex + "\n", 0644);
  CHECK_THAT(refusal([&] { load_key_file(file); }), Contains("mode 0644"));
}

TEST_CASE("load_key_file: bad content, missing files and non-files name the file", "[bridge][key]") {
  using Catch::Matchers::Contains;
  TempDir dir;
  const auto short_file = dir.write("short", kHex.substr(2) + "\n");
  CHECK_THAT(refusal([&] { load_key_file(short_file); }), Contains(short_file.string()) && Contains("found 62"));
  const auto long_file = dir.write("long", std::string(4096, 'a'));
  CHECK_THAT(refusal([&] { load_key_file(long_file); }), Contains(long_file.string()) && Contains("too long"));
  const auto crlf = dir.write("crlf", kHex + "\r\n");
  CHECK_THAT(refusal([&] { load_key_file(crlf); }), Contains("carriage return"));
  const auto bad_hex = dir.write("bad-hex", hex_with(0, 'z') + "\n");
  CHECK_THAT(refusal([&] { load_key_file(bad_hex); }), Contains(bad_hex.string()) && Contains("character 1"));
  const auto empty = dir.write("empty", "");
  CHECK_THAT(refusal([&] { load_key_file(empty); }), Contains("found 0"));
  CHECK_THAT(refusal([&] { load_key_file(dir.path() / "absent"); }),
             Contains("absent") && Contains("cannot open") && Contains("No such file"));
  const auto sub = dir.path() / "a-directory";
  fs::create_directory(sub);
  ::chmod(sub.c_str(), 0700);
  CHECK_THAT(refusal([&] { load_key_file(sub); }), Contains("not a regular file"));
}

TEST_CASE("write_key_file creates a 0600 file that load_key_file reads, and never overwrites", "[bridge][key]") {
  using Catch::Matchers::Contains;
  TempDir dir;
  const auto file = dir.path() / "bridge.key";
  const Key key = generate_key();
  const mode_t old_mask = ::umask(0);  // even with a permissive umask
  write_key_file(file, key);
  ::umask(old_mask);
  struct stat info {};
  REQUIRE(::stat(file.c_str(), &info) == 0);
  CHECK((info.st_mode & 07777) == 0600);
  CHECK(load_key_file(file).bytes == key.bytes);
  CHECK_THAT(refusal([&] { write_key_file(file, generate_key()); }), Contains("exists") && Contains("never"));
  CHECK(load_key_file(file).bytes == key.bytes);
}
