// Runs the datagram fuzz harness over corpus files without libFuzzer, so any compiler (g++ in the normal build)
// replays the corpus as a regression test: `lever_fuzz_datagram_replay DIR_OR_FILE...`. Exits non-zero if an
// input cannot be read; a broken invariant aborts inside the harness.
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <vector>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size);

namespace {

bool run_file(const std::filesystem::path& file) {
  std::ifstream stream(file, std::ios::binary);
  if (!stream) {
    std::fprintf(stderr, "cannot read %s\n", file.c_str());
    return false;
  }
  const std::vector<char> bytes((std::istreambuf_iterator<char>(stream)), std::istreambuf_iterator<char>());
  std::vector<std::uint8_t> input(bytes.begin(), bytes.end());
  LLVMFuzzerTestOneInput(input.data(), input.size());
  return true;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr, "usage: %s DIR_OR_FILE...\n", argv[0]);
    return 2;
  }
  std::size_t count = 0;
  bool ok = true;
  for (int i = 1; i < argc; ++i) {
    const std::filesystem::path path(argv[i]);
    if (std::filesystem::is_directory(path)) {
      for (const auto& entry : std::filesystem::directory_iterator(path)) {
        if (!entry.is_regular_file()) continue;
        ok = run_file(entry.path()) && ok;
        ++count;
      }
    } else {
      ok = run_file(path) && ok;
      ++count;
    }
  }
  // Also the inputs no corpus holds: empty and one byte.
  LLVMFuzzerTestOneInput(nullptr, 0);
  const std::uint8_t one = 0x4C;
  LLVMFuzzerTestOneInput(&one, 1);
  std::printf("replayed %zu input(s) without a finding\n", count);
  return ok && count > 0 ? 0 : 1;
}
