#include "lever/board/gpio_encoder_config.hpp"

#include <string>

#include "gpio_chip.hpp"

namespace lever::board {

namespace {

// Past a 1 ms tick, every edge would wait a tick or more, and the level check forgive as much.
constexpr std::uint32_t kMaxLatencyUs = 1'000;

}  // namespace

std::vector<std::string> GpioEncoderConfig::validate() const {
  std::vector<std::string> problems;
  if (chip.empty()) problems.emplace_back("chip: empty (a path /dev/gpiochipN, a name gpiochipN, or a label)");
  const auto check_line = [&](const char* field, const LineRef& line) {
    if (!line.is_offset() && line.name_value().empty()) problems.emplace_back(std::string(field) + ": empty name");
  };
  check_line("line_a", line_a);
  check_line("line_b", line_b);
  if (line_z) check_line("line_z", *line_z);
  if (line_a == line_b) problems.emplace_back("line_b: the same line as line_a (" + line_b.describe() + ")");
  if (line_z && *line_z == line_a)
    problems.emplace_back("line_z: the same line as line_a (" + line_z->describe() + ")");
  if (line_z && *line_z == line_b)
    problems.emplace_back("line_z: the same line as line_b (" + line_z->describe() + ")");
  if (consumer.empty()) problems.emplace_back("consumer: empty (gpioinfo would show the lines as unnamed users)");
  if (consumer.size() > kMaxGpioConsumer) {
    problems.emplace_back("consumer: " + std::to_string(consumer.size()) + " characters, the kernel keeps " +
                          std::to_string(kMaxGpioConsumer));
  }
  if (edge_latency_us > kMaxLatencyUs) {
    problems.emplace_back("edge_latency_us: " + std::to_string(edge_latency_us) + " is above " +
                          std::to_string(kMaxLatencyUs) + " (every edge would wait a tick or more)");
  }
  return problems;
}

}  // namespace lever::board
