#pragma once
// What a factory returns: the opened object, or why it could not be opened. No half-open objects: a backend
// that exists is open, and one that could not be opened does not exist.
#include <string>
#include <utility>
#include <variant>

namespace lever::board {

struct Error {
  std::string message;  // names the thing and the reason, ready for a log line
  int errno_value = 0;  // 0 when no system call failed
};

template <typename T>
class Result {
 public:
  Result(T value) : v_(std::move(value)) {}      // NOLINT(google-explicit-constructor): return obj;
  Result(Error error) : v_(std::move(error)) {}  // NOLINT(google-explicit-constructor): return Error{...};

  bool ok() const noexcept { return std::holds_alternative<T>(v_); }
  explicit operator bool() const noexcept { return ok(); }
  T& value() & { return std::get<T>(v_); }
  T&& value() && { return std::get<T>(std::move(v_)); }
  const Error& error() const { return std::get<Error>(v_); }

 private:
  std::variant<T, Error> v_;
};

}  // namespace lever::board
