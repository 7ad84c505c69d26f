#pragma once
// The last values of a signal, one a sample period, oldest first; an empty slot is a period with no value.
#include <array>
#include <cstddef>
#include <optional>

namespace lever::view {

class History {
 public:
  static constexpr std::size_t kCapacity = 200;

  void push(std::optional<float> value) noexcept {
    values_[next_] = value;
    next_ = (next_ + 1) % kCapacity;
    if (size_ < kCapacity) ++size_;
  }
  std::size_t size() const noexcept { return size_; }
  // i = 0 is the oldest kept.
  std::optional<float> operator[](std::size_t i) const noexcept {
    return values_[(next_ + kCapacity - size_ + i) % kCapacity];
  }
  void clear() noexcept { *this = History{}; }

 private:
  std::array<std::optional<float>, kCapacity> values_{};
  std::size_t next_ = 0;
  std::size_t size_ = 0;
};

}  // namespace lever::view
