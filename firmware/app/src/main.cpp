// lever-fw: the program a lever controller runs. Loads its TOML configuration and runs the lever on the board's
// hardware. The same firmware against the simulated testbed is lever-fw-sim, a program of the HIL's (hil/fw-sim).
#include <fmt/format.h>

#include <atomic>
#include <csignal>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "lever/app/board_runner.hpp"
#include "lever/app/fw_config.hpp"
#include "lever/app/motor_off.hpp"
#include "lever/app/stats_line.hpp"
#include "lever/board/kernel_preemption.hpp"
#include "lever/board/motor_guard.hpp"
#include "lever/program/choices.hpp"
#include "lever/program/parse.hpp"
#include "lever/program/text.hpp"

namespace {

using namespace lever;

constexpr int kBadInput = program::kBadInput;

std::atomic<bool> g_stop{false};
extern "C" void on_signal(int) { g_stop.store(true); }

}  // namespace

int main(int argc, char** argv) {
  // The motor guard lever-fw starts beside itself (board/motor_guard.hpp): not a user's command, so not in --help.
  if (argc == 3 && std::string_view(argv[1]) == "--motor-guard") return board::run_motor_guard(argv[2]);
  CLI::App app{"lever-fw: the firmware of one lever of the haptic teleoperation testbed (HSI or TOP)."};
  program::describe(app, "lever-fw");
  std::string config_path, can, motor_state;
  std::optional<protocol::Role> role;
  bool check_config = false, stats_json = false, motor_off = false, kernel_check = false;
  app.add_option("--config", config_path, "TOML configuration (docs/lever-fw.md lists every key)")
      ->required()
      ->check(program::path());
  app.add_option("--role", role, "override lever.role: hsi or top")
      ->transform(program::one_of(
          program::Choices<protocol::Role>{{"hsi", protocol::Role::hsi}, {"top", protocol::Role::top}}));
  app.add_option("--can", can, "override board.can.interface");
  std::vector<std::string> sets;
  app.add_option("--set", sets,
                 "override one key, KEY=VALUE with VALUE a TOML value (--set codec.motion.p=0.05 --set "
                 "'board.can.interface=\"vcan0\"'), checked as in the file; repeatable, applied in order after the "
                 "file, before --role and --can")
      ->take_all()
      ->allow_extra_args(false);
  app.add_flag("--check-config", check_config, "validate the configuration and print it, touching no hardware");
  std::string get_key;
  app.add_option("--get", get_key,
                 "validate the configuration and print one key's effective value (a string without its quotes), "
                 "touching no hardware: --get control.position.kp_nm_per_rad")
      ->excludes("--check-config");
  app.add_flag("--stats-json", stats_json, "one JSON status object per line, once a second");
  app.add_flag("--motor-off", motor_off,
               "stop the board's motor (PWM at duty 0 and enabled, driver enable line off) and exit: for the service "
               "manager after lever-fw ended, however it ended")
      ->excludes("--check-config", "--get", "--set");
  app.add_flag("--kernel-check", kernel_check,
               "say which preemption model the kernel runs (the loop needs full or PREEMPT_RT) and exit 0: the "
               "service's ExecStartPre, unsandboxed, where lever-fw itself cannot read /proc/cmdline")
      ->excludes("--check-config", "--motor-off", "--get");
  app.add_option("--motor-state", motor_state,
                 "a file naming the motor and the run: written at start, before the motor is opened; with it, "
                 "--motor-off stops that motor only, and under systemd only its own invocation's (the service: "
                 "/run/lever/INSTANCE/motor)")
      ->check(program::path());
  if (const auto exit_code = program::parse(app, argc, argv)) return *exit_code;

  if (kernel_check) {
    fmt::print("lever-fw: {}\n", board::describe(board::read_kernel_preemption_sources()));
    return 0;
  }
  // Before the configuration is validated: the motor must stop whatever else in the file is wrong.
  if (motor_off) return app::motor_off(config_path, motor_state);

  std::optional<std::string> can_override;
  if (app.count("--can") > 0) can_override = can;
  auto loaded = app::load_fw_config(config_path, {role, can_override, sets});
  if (!loaded.error.empty()) {
    fmt::print(stderr, "lever-fw: {}\n", loaded.error);
    return kBadInput;
  }
  auto& config = loaded.config;
  if (app.count("--get") > 0) {
    const auto value = app::schema_for(config).value_text(get_key);
    if (!value) {
      fmt::print(stderr, "lever-fw: --get: no key '{}' (every key: lever-fw --config FILE --check-config)\n",
                 program::printable(get_key));
      return kBadInput;
    }
    fmt::print("{}\n", *value);
    return 0;
  }
  if (check_config) {
    fmt::print("# lever-fw: {} is valid; the effective configuration:\n{}", config_path,
               app::schema_for(config).print());
    return 0;
  }
  std::signal(SIGINT, on_signal);
  std::signal(SIGTERM, on_signal);
  return app::run_board(config, stats_json, motor_state, g_stop);
}
