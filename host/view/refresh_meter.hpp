#pragma once
// How often the screen is drawn: the pictures a second over the last ten intervals, shown in its header, so a
// screen that cannot keep its refresh rate says so.
#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>

namespace lever::view {

class RefreshMeter {
 public:
  void on_draw(std::int64_t t_us) noexcept {
    times_[next_] = t_us;
    next_ = (next_ + 1) % times_.size();
    if (count_ < times_.size()) ++count_;
  }
  // Unknown until two pictures were drawn.
  std::optional<double> per_second() const noexcept {
    if (count_ < 2) return std::nullopt;
    const std::int64_t newest = times_[(next_ + times_.size() - 1) % times_.size()];
    const std::int64_t oldest = times_[(next_ + times_.size() - count_) % times_.size()];
    if (newest <= oldest) return std::nullopt;
    return static_cast<double>(count_ - 1) * 1e6 / static_cast<double>(newest - oldest);
  }

 private:
  std::array<std::int64_t, 11> times_{};
  std::size_t next_ = 0;
  std::size_t count_ = 0;
};

}  // namespace lever::view
