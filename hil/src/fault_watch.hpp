#pragma once
// What each lever did about lever-hil run's injected faults: when it latched a fault, reached its safe behaviour and
// was re-armed, and whether it ever armed again without a re-arm (what the safety rules forbid).
#include <vector>

#include "lever/hil/simulation.hpp"
#include "sim_levers.hpp"

namespace lever::hil {

class FaultWatch {
 public:
  explicit FaultWatch(const std::vector<FaultSpec>& faults) {
    for (const auto& f : faults) reports_.push_back({f, {}, {}});
  }

  // After the levers' step at scenario time `t`.
  void step(double t, SimLevers& levers);
  void finish(SimResult& result) const { result.faults = reports_; }

 private:
  std::vector<FaultReport> reports_;
};

}  // namespace lever::hil
