// Which preemption model a kernel runs, from the sources an unprivileged lever-fw reads: the version strings and
// configurations here are the ones Debian 12's kernels (6.1.0-*-amd64, -rt-amd64) and a static CONFIG_PREEMPT build
// print.
#include <catch2/catch.hpp>

#include "lever/board/kernel_preemption.hpp"

using lever::board::describe;
using lever::board::KernelPreemptionSources;
using lever::board::Preemption;
using lever::board::preemption_of;

namespace {

constexpr const char* kDebianDynamic = "#1 SMP PREEMPT_DYNAMIC Debian 6.1.192-2 (2026-11-16)";
constexpr const char* kDebianConfig =
    "CONFIG_PREEMPT_BUILD=y\nCONFIG_PREEMPT_VOLUNTARY=y\n# CONFIG_PREEMPT is not set\nCONFIG_PREEMPT_DYNAMIC=y\n";

}  // namespace

TEST_CASE("kernel preemption: Debian's PREEMPT_DYNAMIC kernel boots voluntary unless told preempt=full") {
  KernelPreemptionSources s{kDebianDynamic, "root=/dev/vda rw console=ttyS0", std::nullopt, kDebianConfig};
  CHECK(preemption_of(s) == Preemption::voluntary);
  s.cmdline = "root=/dev/vda rw console=ttyS0 nohz=off preempt=full";
  CHECK(preemption_of(s) == Preemption::full);
  s.cmdline = "preempt=full quiet preempt=voluntary";  // the last one counts
  CHECK(preemption_of(s) == Preemption::voluntary);
  s.cmdline = "preempt=none";
  CHECK(preemption_of(s) == Preemption::voluntary);
}

TEST_CASE("kernel preemption: debugfs's current mode wins over the command line (it may be switched at run time)") {
  KernelPreemptionSources s{kDebianDynamic, "preempt=full", std::string("none voluntary (full)\n"), kDebianConfig};
  CHECK(preemption_of(s) == Preemption::full);
  s.debugfs_preempt = "none (voluntary) full\n";
  CHECK(preemption_of(s) == Preemption::voluntary);
}

TEST_CASE("kernel preemption: a dynamic kernel with no preempt= and no readable configuration is not known") {
  const KernelPreemptionSources s{kDebianDynamic, "quiet", std::nullopt, std::nullopt};
  CHECK(preemption_of(s) == Preemption::unknown);
  CHECK_THAT(describe(s), Catch::Contains("no preempt= on the command line"));
  KernelPreemptionSources full_default = s;
  full_default.build_config = "CONFIG_PREEMPT=y\nCONFIG_PREEMPT_DYNAMIC=y\n";
  CHECK(preemption_of(full_default) == Preemption::full);
}

TEST_CASE("kernel preemption: a hidden command line (systemd's ProcSubset=pid) leaves a dynamic kernel unknown") {
  // The build's default is voluntary, but the hidden command line may hold preempt=full: no guess.
  const KernelPreemptionSources s{kDebianDynamic, std::nullopt, std::nullopt, kDebianConfig};
  CHECK(preemption_of(s) == Preemption::unknown);
  CHECK_THAT(describe(s), Catch::Contains("/proc/cmdline not readable"));
  // A static build needs no command line.
  CHECK(preemption_of({"#1 SMP Debian 5.10.228-1", std::nullopt, std::nullopt, std::nullopt}) == Preemption::voluntary);
}

TEST_CASE("kernel preemption: the line says the model and which source named it") {
  KernelPreemptionSources s{kDebianDynamic, "root=/dev/vda preempt=full", std::nullopt, kDebianConfig};
  CHECK(describe(s) == "kernel preemption: full (preempt= on the kernel command line)");
  s.cmdline = "root=/dev/vda";
  CHECK_THAT(describe(s),
             Catch::StartsWith("warning: the kernel runs the voluntary preemption model (the build's default"));
}

TEST_CASE("kernel preemption: PREEMPT_RT, a static PREEMPT build, and a build that names no preemption") {
  CHECK(preemption_of({"#1 SMP PREEMPT_RT Debian 6.1.192-2 (2026-11-16)", "", std::nullopt, std::nullopt}) ==
        Preemption::realtime);
  CHECK(preemption_of({"#1 SMP PREEMPT Fri Nov 13 10:00:00 UTC 2026", "", std::nullopt, std::nullopt}) ==
        Preemption::full);
  CHECK(preemption_of({"#1 SMP Debian 5.10.228-1 (2026-01-01)", "preempt=full", std::nullopt, std::nullopt}) ==
        Preemption::voluntary);
}
