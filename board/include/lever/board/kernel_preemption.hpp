#pragma once
// Which preemption model the running kernel uses, from what an unprivileged process can read. A real-time priority
// only helps where the kernel lets the loop in: under the voluntary (or no-forced-preemption) model an ordinary
// process inside a system call holds every loop of its CPU until that kernel path yields (docs/deploy.md, "The
// board's kernel").
#include <optional>
#include <string>
#include <string_view>

namespace lever::board {

enum class Preemption {
  full,       // CONFIG_PREEMPT, or PREEMPT_DYNAMIC booted or switched to "full"
  realtime,   // PREEMPT_RT
  voluntary,  // CONFIG_PREEMPT_VOLUNTARY or CONFIG_PREEMPT_NONE, or PREEMPT_DYNAMIC in one of those modes
  unknown,    // PREEMPT_DYNAMIC whose mode none of the sources names
};

struct KernelPreemptionSources {
  std::string uname_version;                   // uname(2)'s version: "#1 SMP PREEMPT_DYNAMIC Debian 6.1.192-2 ..."
  std::optional<std::string> cmdline;          // /proc/cmdline (hidden under systemd's ProcSubset=pid)
  std::optional<std::string> debugfs_preempt;  // /sys/kernel/debug/sched/preempt: "none voluntary (full)"
  std::optional<std::string> build_config;     // /boot/config-RELEASE
};

// The model the sources name. In order: debugfs's current mode (PREEMPT_DYNAMIC, may have been switched at run
// time), PREEMPT_RT in the version, for PREEMPT_DYNAMIC the cmdline's preempt= and else the build's default (only
// where the cmdline could be read: a hidden one may hold preempt=), a static PREEMPT in the version; a version
// without PREEMPT is a voluntary or none build.
Preemption preemption_of(const KernelPreemptionSources& sources);

// The running kernel's sources, each read where it is readable.
KernelPreemptionSources read_kernel_preemption_sources();

std::string_view name(Preemption p) noexcept;

// One line for a person: the model and the source that named it; for voluntary and unknown, what to do.
std::string describe(const KernelPreemptionSources& sources);

}  // namespace lever::board
