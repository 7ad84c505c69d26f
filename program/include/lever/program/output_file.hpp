#pragma once
// Every file a program writes. The target is a regular file or absent: it is written beside itself into a
// temporary, fsync'd and renamed over it, so a reader never sees half a file. Anything else is refused with
// exit 2 before a byte is computed: a device, a FIFO or socket, a directory, a symbolic link (the rename would
// replace the link, not its target), the input file itself, a directory that does not exist. "-" is stdout.
// Memory stays bounded (a fixed buffer, flushed as it fills), and SIGINT, SIGTERM and SIGHUP remove the
// temporary before the signal's default action: nothing hidden is left behind.
#include <cstddef>
#include <string>
#include <string_view>
#include <vector>

namespace lever::program {

class OutputFile {
 public:
  // Checks the target and creates the temporary. `inputs` are files the program reads: the target must be
  // none of them. `what` names the file in messages ("the trace", "--out"). Throws BadInput for a target the
  // program refuses, std::runtime_error (with errno's reason) when the system fails.
  explicit OutputFile(std::string path, std::string what = "output", const std::vector<std::string>& inputs = {});
  ~OutputFile();  // without commit(): the temporary is removed, the target untouched
  OutputFile(const OutputFile&) = delete;
  OutputFile& operator=(const OutputFile&) = delete;

  void write(std::string_view data);
  // Flushes, fsyncs and renames the temporary over the target (stdout: flushes). Throws on failure.
  void commit();

  bool is_stdout() const noexcept { return fd_ == 1; }
  const std::string& path() const noexcept { return path_; }

  // The whole of `content`, at once.
  static void write_all(const std::string& path, std::string_view content, const std::string& what = "output",
                        const std::vector<std::string>& inputs = {});

 private:
  void flush();
  [[noreturn]] void fail(const char* doing, int error);

  std::string path_, what_, temp_;
  int fd_ = -1;
  int slot_ = -1;  // in the signal handler's list of temporaries
  bool committed_ = false;
  std::vector<char> buffer_;
};

// For a file a program reads: "-" is stdin. Throws BadInput for a directory or a missing file.
void check_input_path(const std::string& path, const std::string& what);

}  // namespace lever::program
